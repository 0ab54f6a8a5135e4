"""Generate the two synthetic accelerograms shipped in ``rockbench/data/records``.

They are made here from fixed formulas and a fixed random seed, so they carry no
third-party rights and need no download; running this script again rewrites
byte-identical files (NumPy's PCG64 generator is stable across versions for
``standard_normal``)::

    python benchmarks/make_records.py            # writes rockbench/data/records/
    python benchmarks/make_records.py --check    # verifies the committed files

``synthetic-1``: 10 s at 100 Hz, Gaussian white noise (seed 20250901) filtered
by a Kanai–Tajimi soil filter (ω_g = 5π rad/s, ζ_g = 0.6) and a Clough–Penzien
high-pass (ω_f = 0.5π rad/s, ζ_f = 0.6), shaped by a Jennings envelope (t²
rise to 1.5 s, flat to 5 s, exp(−0.5 (t − 5)) decay, cosine taper over the
last 0.5 s), scaled to a PGA of 0.35 g.

``synthetic-2``: 10 s at 100 Hz, a near-fault-like record: the
Mavroeidis–Papageorgiou (2003) velocity pulse (f_p = 1 Hz, γ = 2, ν = 90°,
centred at t = 3 s, PGV 0.5 m/s) differentiated analytically, plus the
synthetic-1 type of noise (seed 20250902) at 0.05 g PGA.

Each is written as a PEER NGA ``.AT2`` file (units g, 5 values per line,
``%15.7E``) and as a two-column CSV ``t,acc`` in m/s² holding exactly the
same values (the AT2 numbers times 9.80665).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

G = 9.80665
DT = 0.01
N = 1000
OUT = Path(__file__).resolve().parents[1] / "rockbench" / "data" / "records"


def kanai_tajimi_noise(seed: int, n: int = N, dt: float = DT) -> np.ndarray:
    """Kanai–Tajimi + Clough–Penzien filtered white noise (unit-less, not enveloped).

    Parameters
    ----------
    seed : int
        Seed of ``numpy.random.default_rng``.
    n : int
        Number of samples.
    dt : float
        Time step (s).
    """
    rng = np.random.default_rng(seed)
    white = rng.standard_normal(n)
    w = 2.0 * np.pi * np.fft.rfftfreq(n, dt)
    wg, zg, wf, zf = 5.0 * np.pi, 0.6, 0.5 * np.pi, 0.6
    kt = (wg**2 + 2j * zg * wg * w) / (wg**2 - w**2 + 2j * zg * wg * w)
    cp = w**2 / (wf**2 - w**2 + 2j * zf * wf * w)
    return np.fft.irfft(np.fft.rfft(white) * kt * cp, n)


def jennings_envelope(t: np.ndarray) -> np.ndarray:
    """Rise t² to 1.5 s, flat to 5 s, exponential decay, cosine taper over the last 0.5 s."""
    env = np.where(t < 1.5, (t / 1.5) ** 2, np.where(t < 5.0, 1.0, np.exp(-0.5 * (t - 5.0))))
    t_end = t[-1]
    taper = np.where(t > t_end - 0.5, 0.5 * (1 + np.cos(np.pi * (t - (t_end - 0.5)) / 0.5)), 1.0)
    return env * taper


def synthetic_1() -> np.ndarray:
    """Enveloped Kanai–Tajimi noise, PGA 0.35 g (in g)."""
    t = DT * np.arange(N)
    a = kanai_tajimi_noise(20250901) * jennings_envelope(t)
    return 0.35 * a / np.max(np.abs(a))


def mp_pulse_acceleration(t: np.ndarray, *, fp: float = 1.0, gamma: float = 2.0,
                          nu: float = 0.5 * np.pi, t0: float = 3.0,
                          pgv: float = 0.5) -> np.ndarray:
    """Acceleration (m/s²) of the Mavroeidis–Papageorgiou velocity pulse.

    v(t) = (A/2) [1 + cos(2π f_p (t − t0)/γ)] cos(2π f_p (t − t0) + ν) on
    |t − t0| ≤ γ/(2 f_p), 0 elsewhere; its exact derivative is returned.
    """
    tau = t - t0
    inside = np.abs(tau) <= gamma / (2.0 * fp)
    a1 = 2.0 * np.pi * fp / gamma
    a2 = 2.0 * np.pi * fp
    env, denv = 1.0 + np.cos(a1 * tau), -a1 * np.sin(a1 * tau)
    car, dcar = np.cos(a2 * tau + nu), -a2 * np.sin(a2 * tau + nu)
    acc = 0.5 * pgv * (denv * car + env * dcar)
    return np.where(inside, acc, 0.0)


def synthetic_2() -> np.ndarray:
    """Near-fault-like record: velocity pulse plus 0.05 g noise (in g)."""
    t = DT * np.arange(N)
    noise = kanai_tajimi_noise(20250902) * jennings_envelope(t)
    noise *= 0.05 / np.max(np.abs(noise))
    return mp_pulse_acceleration(t) / G + noise


def at2_text(acc_g: np.ndarray, title: str) -> str:
    """A PEER NGA AT2 file (4 header lines, 5 values per line)."""
    lines = [
        "PEER NGA STRONG MOTION DATABASE RECORD (format only: synthetic, see README)",
        f"{title}",
        "ACCELERATION TIME SERIES IN UNITS OF G",
        f"NPTS= {acc_g.size:6d}, DT= {DT:8.4f} SEC",
    ]
    vals = [f"{x + 0.0:15.7E}" for x in acc_g]  # + 0.0 turns -0.0 into 0.0
    lines += ["".join(vals[i:i + 5]) for i in range(0, len(vals), 5)]
    return "\n".join(lines) + "\n"


def csv_text(acc_g: np.ndarray, title: str) -> str:
    """Two-column CSV t (s), acc (m/s²) with the AT2 values × 9.80665."""
    rounded = np.array([float(f"{x + 0.0:15.7E}") for x in acc_g]) + 0.0
    rows = [f"# {title}", "# units: m/s2 (AT2 values in g times 9.80665)", "t,acc"]
    rows += [f"{DT * i:.2f},{G * a:.10e}" for i, a in enumerate(rounded)]
    return "\n".join(rows) + "\n"


RECORDS = {
    "synthetic-1": (synthetic_1, "SYNTHETIC-1 rockbench: Kanai-Tajimi filtered enveloped "
                                 "white noise, seed 20250901, PGA 0.35 g, 10 s at 100 Hz"),
    "synthetic-2": (synthetic_2, "SYNTHETIC-2 rockbench: Mavroeidis-Papageorgiou velocity pulse "
                                 "fp=1 Hz PGV 0.5 m/s + 0.05 g noise, seed 20250902, 10 s"),
}


def main(argv: list[str] | None = None) -> int:
    """Write (or with ``--check`` compare) the record files; returns the exit status."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=OUT, help=f"directory (default: {OUT})")
    ap.add_argument("--check", action="store_true", help="compare instead of writing")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    bad = 0
    for name, (make, title) in RECORDS.items():
        acc = make()
        for suffix, text in ((".AT2", at2_text(acc, title)), (".csv", csv_text(acc, title))):
            path = args.out / f"{name}{suffix}"
            if args.check:
                same = path.exists() and path.read_text() == text
                bad += not same
                print(f"{path}: {'ok' if same else 'DIFFERS'}")
            else:
                path.write_text(text)
                print(f"wrote {path}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
