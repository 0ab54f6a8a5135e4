"""The README's quick start stays true: CI runs exactly its test command."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _quick_start_commands() -> list[str]:
    text = (ROOT / "README.md").read_text()
    block = text.split("## Quick start", 1)[1].split("```bash", 1)[1].split("```", 1)[0]
    return [ln.strip() for ln in block.splitlines() if ln.strip() and not ln.startswith("#")]


def test_quick_start_is_two_commands_main_job_and_tests():
    compare, tests = _quick_start_commands()
    assert "rockbench compare" in compare and "--out" in compare
    assert "pytest" in tests


def test_ci_runs_the_readme_test_command():
    _, tests = _quick_start_commands()
    ci = (ROOT / ".ci" / "run").read_text()
    assert tests in ci.splitlines()


def test_readme_names_only_existing_suites_and_commands():
    from rockbench.cli import commands
    from rockbench.scenarios import suites

    text = (ROOT / "README.md").read_text()
    code = "\n".join(re.findall(r"```bash\n(.*?)```", text, flags=re.S))
    for suite in re.findall(r"--suite ([a-z0-9-]+)", code):
        assert suite in suites() or suite == "paper-sensitivity", suite
    for cmd in re.findall(r"^(?:\S*/)?rockbench ([a-z]+)", code, flags=re.M):
        assert cmd in commands(), cmd


def test_readme_commands_parse():
    # every `rockbench ...` line of the README is accepted by the real parser
    # (options that were renamed or removed would fail here, nothing is run)
    import shlex

    from rockbench.cli import build_parser

    text = (ROOT / "README.md").read_text()
    code = "\n".join(re.findall(r"```bash\n(.*?)```", text, flags=re.S))
    lines = [ln.split("#", 1)[0] for ln in code.splitlines()]
    commands = [shlex.split(ln.split("rockbench ", 1)[1]) for ln in lines if "rockbench " in ln]
    assert len(commands) >= 10
    parser = build_parser()
    for argv in commands:
        argv = [a for a in argv if a != "&&"]
        parser.parse_args(argv)  # SystemExit (status 2) on an unknown option
