"""Catalog scenarios driven by the synthetic accelerograms shipped with rockbench.

The records live in ``rockbench/data/records`` (made by
``benchmarks/make_records.py``; see the README there): ``synthetic-1``
(Kanai–Tajimi filtered, enveloped noise, PGA 0.35 g) and ``synthetic-2``
(near-fault-like velocity pulse plus noise, PGA ≈ 0.31 g), each as a PEER
``.AT2`` file (units g) and a two-column CSV (m/s²). Nothing is downloaded.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from rockbench.geometry import Block, single
from rockbench.scenarios.excitation import Record
from rockbench.scenarios.model import Contact, Scenario

__all__ = ["RECORDS_DIR", "record_path", "record_scenarios", "RECORD_CASES"]

#: Folder of the shipped synthetic records.
RECORDS_DIR = Path(__file__).resolve().parent.parent / "data" / "records"

#: name → (record file, block key, scale, description of the block)
RECORD_CASES: dict[str, tuple[str, str, float]] = {
    "record-synth1-b2": ("synthetic-1.AT2", "b2", 3.0),
    "record-synth2-b2": ("synthetic-2.AT2", "b2", 2.5),
    "record-synth1-single2": ("synthetic-1.csv", "single2", 1.0),
}
_BLOCKS = {
    "b2": (Block(0.50, 0.20, 1.00, mass=1.0), "B2 block (0.5 × 1.0 m, 1 kg)"),
    "single2": (Block(width=0.17, depth=0.502, height=1.0, density=2670.0),
                "Single #2 granite block (0.17 × 1.0 m)"),
}
RECORD_DURATION = 12.0


def record_path(file: str) -> Path:
    """Absolute path of a shipped record file (e.g. ``"synthetic-1.AT2"``)."""
    return RECORDS_DIR / file


def record_scenarios() -> dict[str, Callable[[], Scenario]]:
    """Catalog entries (name → factory) of the record scenarios."""
    out: dict[str, Callable[[], Scenario]] = {}
    for name, (file, key, scale) in RECORD_CASES.items():
        def make(name: str = name, file: str = file, key: str = key,
                 scale: float = scale) -> Scenario:
            block, what = _BLOCKS[key]
            exc = Record.from_file(record_path(file), scale=scale)
            return Scenario(name=name, geometry=single(block), contact=Contact(friction=1.0),
                            excitation=exc, duration=RECORD_DURATION, output_rate=1000.0,
                            description=f"{what} under the synthetic record {file} × {scale:g} "
                                        f"(rockbench/data/records)")
        out[name] = make
    return out
