"""dem2d engine plugin: a Distinct Element Method for planar rigid blocks (3DEC-style rocking).

The paper's DEM column comes from 3DEC, which has no open equivalent; this is
our own two-dimensional DEM with the same ingredients (paper-brief.md, "DEM"):
rigid convex blocks (rectangles, or octagons when chamfered) in the x–z plane;
soft contacts between facing block edges, each discretised into ``subcontacts``
points with normal and shear springs per unit area (k_n, k_s) over their
tributary areas; zero tension; Mohr–Coulomb slip with the scenario's friction;
stiffness-proportional (Rayleigh β) damping at the contacts; explicit central
differences with the CFL-bounded step; and a kinematic base driven by the
excitation's displacement, so that the base velocity seen by the contacts is
the exact mean velocity of each step. The inner loop is
:mod:`rockbench.engines.dem2d_kernels` (numba-compiled when available; the
``dem`` extra installs numba).

Time step. 3DEC uses Δt = safety · sqrt(m_min / k_max). For a rigid block the
mass that a contact point "feels" is the effective mass
m_eff = 1 / (1/m + R²/I) (R: the farthest vertex from the centroid), the
rigid-body analogue of 3DEC's gridpoint mass, and the stiffest spring is a
whole face in contact, k_max = max(k_n, k_s) · width · depth. With damping the
central-difference limit shrinks by sqrt(1 + ζ²) − ζ, ζ = β ω_max / 2, which is
applied too. The step is then rounded down to a whole number of steps per
output interval.

Choosing β. Damping proportional to the contact stiffness (C = β K) gives a
mode of circular frequency ω the modal damping ratio β ω / 2. The paper writes
β = ζ/ω (3DEC's Rayleigh convention, β = ζ_min / ω_min, in which the mass term
supplies the other half); the knob follows that convention: β = ζ / ω, so the
contact mode itself gets a modal ratio ζ / 2. Here ω is the
vertical contact frequency of the bottom block on its whole base face,
ω_c = sqrt(k_n · width · depth / m), and ``damping_ratio`` is ζ. For the
paper's Single #2 block with k_n = 1e9 N/m³, ω_c = 612 rad/s, so the paper's
β = 2.25e-4 s is ζ = 0.138; the default ζ = 0.14 reproduces it (β = 2.29e-4 s)
and scales it to other blocks (the preset ``paper`` sets β = 2.25e-4 s for every
block instead). β is a contact property: it is not tuned to reproduce
Housner's η. A soft contact dissipates less at an impact than Housner's
perfectly inelastic impact (the paper's finding for DEM); the benchmark shows
by how much (benchmarks/calibrate_dem2d.py). More damping does not close the
gap: on B2 the first post-impact peak is 1.9 × Housner's at ζ = 0.14 and
still 1.3 × at β = 1e-3 s (ζ = β ω_c = 10), after which dashpots stiffen the impact and
dissipate less again.

Known DEM behaviours (measured, not bugs): with k_n = 1e9 N/m³ a heavy block
on a narrow base (Single #2: 228 kg on 0.17 m × 0.502 m) is compliant enough
to rotate visibly before uplift (its base face lifts progressively from a
third of the uplift moment on, as on a Winkler foundation), so a base pulse
at 0.8 × g tan λ rotates it by ~0.07 λ and the peaks of the weaker pulses grow;
k_n = 1e11 N/m³ removes that part.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from rockbench.engines import dem2d_kernels as K
from rockbench.engines.base import Capabilities, Engine
from rockbench.engines.settings import EngineSettings
from rockbench.errors import UnsupportedScenario
from rockbench.scenarios import Scenario

__all__ = ["Dem2dEngine", "Dem2dSettings"]

#: Steps of base displacement evaluated at once (one vectorised call per chunk;
#: 160 kB of float64).
_BASE_CHUNK = 20_000


@dataclass(frozen=True)
class Dem2dSettings(EngineSettings):
    """Knobs of the dem2d engine (defaults = the ``accurate`` preset).

    Presets: ``accurate`` (the defaults: the paper's k_n = k_s = 1e9 N/m³,
    5 sub-contacts, ζ = 0.14, safety 0.2), ``fast`` (safety 0.5: 2–4 × fewer
    steps, single-block results within 0.03 λ of ``accurate``), ``fine``
    (10 sub-contacts, as the literature recommends) and ``paper`` (β fixed at
    the paper's 2.25e-4 s for every block; heavily damped and slow for the
    1 kg catalog blocks, whose contact frequency is 16 × Single #2's).

    Parameters
    ----------
    subcontacts : int
        Sub-contacts per contact edge (≥ 2), spread over the overlap of the
        two facing edges, ends included (the ends are the rocking pivots).
        The literature recommends ≥ 10 for smooth rocking; the response of a
        block rocking on its corners depends little on it (see the calibration).
    kn : float
        Normal stiffness per unit area (N/m³); each sub-contact's spring is
        k_n times its tributary area. The paper's Table 5: 1e9.
    ks : float
        Shear stiffness per unit area (N/m³), incremental (3DEC's model).
    damping_ratio : float
        ζ of the stiffness-proportional contact damping in the paper's
        convention β = ζ / ω_c, ω_c the bottom block's vertical contact
        frequency (module docstring). The default 0.14 gives the paper's
        β = 2.25e-4 s for Single #2. Ignored when ``beta`` is given.
    beta : float or None
        Stiffness-proportional damping coefficient β in s (dashpots β k_n A and
        β k_s A at each sub-contact); None: from ``damping_ratio``.
    safety : float
        Δt = safety · sqrt(m_eff,min / k_max) · (sqrt(1 + ζ_max²) − ζ_max);
        the central-difference stability limit is safety = 2; 3DEC uses 0.2.
    timestep : float or None
        Explicit time step in s (overrides ``safety``; still rounded down to a
        whole number of steps per output interval). Steps above the stability
        limit blow up (status ``unstable``).
    """

    subcontacts: int = 5
    kn: float = 1e9
    ks: float = 1e9
    damping_ratio: float = 0.14
    beta: float | None = None
    safety: float = 0.2
    timestep: float | None = None

    def __post_init__(self) -> None:
        if self.subcontacts < 2:
            raise ValueError(f"subcontacts must be >= 2, got {self.subcontacts!r}")
        for name in ("kn", "ks"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v!r}")
        if not (math.isfinite(self.damping_ratio) and self.damping_ratio >= 0):
            raise ValueError(f"damping_ratio must be finite and >= 0, got {self.damping_ratio!r}")
        if self.beta is not None and not (math.isfinite(self.beta) and self.beta >= 0):
            raise ValueError(f"beta must be finite and >= 0, got {self.beta!r}")
        if not (math.isfinite(self.safety) and 0 < self.safety <= 2.0):
            raise ValueError(f"safety must be in (0, 2], got {self.safety!r}")
        if self.timestep is not None and not (math.isfinite(self.timestep)
                                              and self.timestep > 0):
            raise ValueError(f"timestep must be finite and > 0, got {self.timestep!r}")


class Dem2dEngine(Engine):
    """Planar Distinct Element Method: rigid blocks on penalty sub-contacts (3DEC-style)."""

    name: ClassVar[str] = "dem2d"
    capabilities: ClassVar[Capabilities] = Capabilities(dimensions=2, max_blocks=None,
                                                        chamfer=True)
    Settings: ClassVar[type[EngineSettings]] = Dem2dSettings
    presets: ClassVar[dict[str, dict[str, Any]]] = {
        "accurate": {},
        "fast": {"safety": 0.5},
        "fine": {"subcontacts": 10},
        "paper": {"subcontacts": 5, "kn": 1e9, "ks": 1e9, "beta": 2.25e-4, "safety": 0.2},
    }
    # numba is optional (the kernels run interpreted without it, slowly), hence no
    # ``requires``; the extra installs it and version() says whether it is used
    extra: ClassVar[str] = "dem"
    # measured with benchmarks/calibrate_dem2d.py (accurate preset, N = 5 sub-contacts);
    # keep in step with the README's engine table
    known_failures: ClassVar[dict[str, str]] = {
        # DEM penalty contacts under-dissipate at impacts, as the paper reports for 3DEC
        "free_rocking": "DEM under-dissipates at impacts: impacts 2-3 are +24 %/+41 % late "
                        "on B2 (limit 2 %)",
        "forced_peak": "DEM: +24 % peak on the 3 Hz/8 mm pulse (compliance at k_n = 1e9 N/m3 "
                       "plus under-dissipation at the first impact)",
        "subthreshold": "DEM soft contact: 0.067 lambda rotation at 0.8 x the uplift "
                        "threshold (elastic-foundation rocking; passes at k_n = 1e11)",
    }

    def __init__(self) -> None:
        self._state: dict[str, Any] = {}
        self._poses = np.zeros((0, 7))
        self._exc: Any = None
        self._dt = 0.0
        self._nb = 0
        self._buf = np.zeros(0)
        self._buf_start = 0
        self._drive_end = 0
        self._step_index = -1

    @classmethod
    def version(cls) -> str:
        """Version of the engine (rockbench's) and whether its loop is compiled."""
        import rockbench

        if K.HAVE_NUMBA:
            return f"{rockbench.__version__} (numba {cls.library('numba').__version__})"
        return f"{rockbench.__version__} (interpreted, without numba)"

    # ------------------------------------------------------------------ hooks
    def _check_supported(self, scenario: Scenario) -> None:
        """Refuse contact restitution > 0: a penalty DEM has no restitution parameter.

        Bounce comes out of the springs and the damping; asking for a
        coefficient of restitution cannot be honoured, so it is refused rather
        than ignored.
        """
        if scenario.contact.restitution > 0.0:
            raise UnsupportedScenario(
                "dem2d has no restitution coefficient (impacts follow from the contact "
                "springs and β damping); use restitution = 0"
            )

    @staticmethod
    def time_step(scenario: Scenario, s: Dem2dSettings) -> tuple[float, float]:
        """CFL-bounded time step and β for ``scenario`` (before output-rate rounding)."""
        blocks = scenario.blocks
        bottom = blocks[0]
        omega_c = math.sqrt(s.kn * bottom.width * bottom.depth / bottom.m)
        beta = s.beta if s.beta is not None else s.damping_ratio / omega_c
        k_max = max(s.kn, s.ks) * max(b.width * b.depth for b in blocks)
        m_eff = min(1.0 / (1.0 / b.m + (b.b ** 2 + b.h ** 2) / b.inertia[1]) for b in blocks)
        if s.timestep is not None:
            return float(s.timestep), beta
        omega_max = math.sqrt(k_max / m_eff)
        zeta = 0.5 * beta * omega_max
        return s.safety * math.sqrt(m_eff / k_max) * (math.sqrt(1 + zeta * zeta) - zeta), beta

    def _build(self, scenario: Scenario, settings: EngineSettings) -> float:
        s: Dem2dSettings = settings  # type: ignore[assignment]
        dt_max, beta = self.time_step(scenario, s)
        k = max(1, math.ceil(1.0 / (scenario.output_rate * dt_max) - 1e-9))
        dt = 1.0 / (scenario.output_rate * k)
        blocks = scenario.blocks
        nb = len(blocks)
        exc = scenario.excitation
        h_tot = scenario.stack.total_height
        w_max = max(b.width for b in blocks)
        t_end = min(exc.end_time, scenario.duration) if not exc.is_free else 0.0
        u_max = exc.motion_bounds(scenario.duration)[0]
        # base: a box whose top face is z = 0, wide enough for a toppled stack
        half = 2.0 * (h_tot + w_max) + u_max + 1.0
        thick = max(1.0, 0.5 * h_tot)
        profiles = [np.asarray(b.profile(), float) for b in blocks]
        profiles.append(np.array([[-half, -0.5 * thick], [half, -0.5 * thick],
                                  [half, 0.5 * thick], [-half, 0.5 * thick]]))
        kmax = max(p.shape[0] for p in profiles)
        nbody = nb + 1
        lverts = np.zeros((nbody, kmax, 2))
        lnorm = np.zeros((nbody, kmax, 2))
        nverts = np.zeros(nbody, np.int64)
        radius = np.zeros(nbody)
        for b, prof in enumerate(profiles):
            nv = prof.shape[0]
            nverts[b] = nv
            lverts[b, :nv] = prof
            e = np.roll(prof, -1, axis=0) - prof
            # outward normal of a counter-clockwise edge (e_x, e_z) is (e_z, −e_x)
            nrm = np.column_stack([e[:, 1], -e[:, 0]])
            lnorm[b, :nv] = nrm / np.linalg.norm(nrm, axis=1, keepdims=True)
            radius[b] = float(np.max(np.linalg.norm(prof, axis=1)))
        # a little slack in the broad phase so that no touching pair is skipped
        radius *= 1.0 + 1e-6
        radius += 1e-6

        centroids, th0 = scenario.initial_poses()
        pos = np.zeros((nbody, 3))
        pos[:nb, 0:2] = centroids
        pos[:nb, 2] = th0
        pos[nb] = (0.0, -0.5 * thick, 0.0)
        vel = np.zeros((nbody, 3))
        inv_m = np.zeros(nbody)
        inv_i = np.zeros(nbody)
        for b, blk in enumerate(blocks):
            inv_m[b] = 1.0 / blk.m
            inv_i[b] = 1.0 / float(blk.inertia[1])
        # every block against the base and against every other block (upper first)
        pairs, depth = [], []
        for i in range(nb):
            pairs.append((i, nb))
            depth.append(blocks[i].depth)
            for j in range(i):
                pairs.append((i, j))
                depth.append(min(blocks[i].depth, blocks[j].depth))
        npairs = len(pairs)
        self._state = dict(
            pos=pos, vel=vel, inv_m=inv_m, inv_i=inv_i, lverts=lverts, lnorm=lnorm,
            nverts=nverts, radius=radius, pairs=np.array(pairs, np.int64),
            pair_depth=np.array(depth, float), pair_edges=np.full(npairs, -1, np.int64),
            shear=np.zeros((npairs, int(s.subcontacts))), kn=float(s.kn), ks=float(s.ks),
            mu=float(scenario.contact.friction), beta=float(beta), g=float(scenario.g),
        )
        # the kernel writes the blocks' poses after every call (read for free)
        self._poses = np.zeros((nb, 7))
        K.write_poses(pos, self._poses)
        self._args = (pos, vel, inv_m, inv_i, lverts, lnorm, nverts, radius,
                      self._state["pairs"], self._state["pair_depth"],
                      self._state["pair_edges"], self._state["shear"], float(s.kn),
                      float(s.ks), float(scenario.contact.friction), float(beta),
                      float(scenario.g), self._poses)
        self._exc = exc
        self._dt = dt
        self._nb = nb
        self._buf = np.zeros(0)
        self._buf_start = 0
        # last step that may be driven (the run's end, or the first output
        # sample after the excitation's): chunks stop there
        self._drive_end = int(math.ceil(t_end / dt)) + k + 1
        self._step_index = -1
        self._still = np.zeros(0)
        return dt

    def _base_positions(self, k0: int, n: int) -> np.ndarray:
        """u_g at the global steps k0 … k0 + n − 1 (exact displacement, no drift).

        Served from a buffer of u_g(k Δt) for whole chunks of global step
        indices k (``_BASE_CHUNK`` at a time, no further than the last step
        that may be driven; refilled from k0 when the request leaves it): an
        excitation's vectorised evaluation has a fixed cost (tens of µs) that
        would otherwise dominate the few steps of one output sample. Every
        value is ``displacement(k · Δt)`` of its own global step index, as if
        the whole run were evaluated at once.
        """
        i = k0 - self._buf_start
        if i < 0 or i + n > self._buf.size:
            self._buf_start = k0
            steps = k0 + np.arange(max(n, min(_BASE_CHUNK, self._drive_end - k0)))
            self._buf = np.asarray(self._exc.displacement(steps * self._dt), float)
            i = 0
        return self._buf[i:i + n]

    def _drive_base(self, t: float, dt: float) -> None:
        # only remember the step; _advance(1) takes the base position from the
        # buffer of precomputed displacements
        self._step_index = int(round(t / dt))

    def _advance_driven(self, t0: float, n: int, dt: float) -> None:
        """Take ``n`` steps from ``t0`` with the base driven, in one compiled call.

        Optional hook (proposed for the base class): replaces n pairs of
        ``_drive_base(t, dt)`` + ``_advance(1)`` by one call. The base
        positions of global steps k0 … k0 + n − 1 (k0 = t0 / Δt) are a slice of
        the chunk buffer of :meth:`_base_positions` (inlined: this runs once
        per output sample, a few compiled steps of well under a µs each).
        """
        k0 = int(round(t0 / dt))
        i = k0 - self._buf_start
        if i < 0 or i + n > self._buf.size:
            K.advance(n, self._dt, *self._args, self._base_positions(k0, n))
        else:
            K.advance(n, self._dt, *self._args, self._buf[i:i + n])

    def _sample_free(self, out: np.ndarray, k: int) -> None:
        """All ``len(out)`` samples of ``k`` still-base steps in one compiled call."""
        K.sample(out.shape[0], k, self._dt, *self._args, self._still, out)

    def _sample_driven(self, out: np.ndarray, step0: int, k: int, dt: float) -> None:
        """All ``len(out)`` driven samples in one compiled call.

        The base positions of global steps step0 … step0 + m·k − 1 come from
        the chunk buffer of :meth:`_base_positions`, as in :meth:`_advance_driven`.
        """
        K.sample(out.shape[0], k, self._dt, *self._args,
                 self._base_positions(step0, out.shape[0] * k), out)

    def _fix_base(self) -> bool:
        self._step_index = -1
        return True

    def _advance(self, n: int) -> None:
        k = self._step_index
        if k < 0:  # base still
            K.advance(n, self._dt, *self._args, self._still)
            return
        K.advance(n, self._dt, *self._args, self._base_positions(k, n))
        self._step_index = k + n

    def _read_poses(self) -> np.ndarray:
        # written by the kernel after every advance (and by _build at the start)
        return self._poses

    def _teardown(self) -> None:
        self._state = {}
        self._args = ()
        self._exc = None
