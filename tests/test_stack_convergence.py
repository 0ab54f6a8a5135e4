"""benchmarks/stack_convergence.py's Markdown section: rows of engines not re-run are kept."""

from __future__ import annotations

from pathlib import Path

from benchmarks.stack_convergence import PER_CASE, Row, Variant, markdown, write_section

CASES = ["stack-pulse-5.0hz-4mm", "stack-sine-5.0hz-4mm"]


def _row(engine: str, error: float) -> Row:
    v = Variant(engine, f"compliance={error:g}", {"compliance": error} if engine == "dem2d"
                else {"timestep": error})
    return Row(v, error, error, error, 0.0, 0.0, 1.0,
               {c: (error, -error) for c in CASES})


def _engines(section: str, per_case: bool) -> list[str]:
    part = section.split(PER_CASE)[1 if per_case else 0]
    return [line.split(" | ")[0][2:] for line in part.splitlines()
            if line.startswith("| ") and not line.startswith(("| engine", "|---"))]


def test_an_engine_run_alone_keeps_the_others_rows(tmp_path: Path) -> None:
    out = tmp_path / "RESULTS.md"
    out.write_text("# results\n\n## Other\n\nkept\n", encoding="utf-8")
    write_section(markdown([_row("pymunk", 0.01), _row("dem2d", 0.02)], CASES, "first"), out)
    write_section(markdown([_row("dem2d", 0.03)], CASES, "second"), out)
    text = out.read_text(encoding="utf-8")
    assert text.startswith("# results\n\n## Other\n\nkept\n")  # the other section stays
    for per_case in (False, True):
        # pymunk's row kept, in the engines' order, dem2d's replaced
        assert _engines(text.split("## Stack")[1], per_case) == ["pymunk", "dem2d"]
    assert "compliance=0.03" in text and "compliance=0.02" not in text
    assert "second Rows of pymunk kept from the previous run." in text
    # the same engines again: the section is the new one, nothing added
    write_section(markdown([_row("pymunk", 0.04), _row("dem2d", 0.05)], CASES, "third"), out)
    text = out.read_text(encoding="utf-8")
    assert "kept from the previous run" not in text and "timestep=0.01" not in text
