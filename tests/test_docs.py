"""The README's quick start stays true: CI runs exactly its test command."""

import re
from pathlib import Path

import pytest

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
    for cmd in re.findall(r"^(?:\S*/)?rockbench ([a-z0-9-]+)", code, flags=re.M):
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


def _architecture_layers() -> list[list[str]]:
    """The layers the README's Architecture block names, bottom first: the names at the
    head of each unindented line (``runner | store | presets``, ``geometry/``...)."""
    text = (ROOT / "README.md").read_text()
    block = text.split("## Architecture", 1)[1].split("```", 2)[1]
    head = re.compile(r"^([a-z_]+/?(?:(?:, | \| )[a-z_]+/?)*)(?=\s|$)")
    layers = []
    for line in block.splitlines():
        if not line.strip() or line[0].isspace():
            continue  # a description carried over from the line above
        m = head.match(line)
        assert m, f"an Architecture line without a layer: {line!r}"
        layers.append(re.split(r", | \| ", m.group(1)))
    return layers


def test_readme_architecture_is_the_import_contract():
    # the README's Architecture block names the layers of the import-linter contract in
    # pyproject.toml, bottom up, and each name is the package (name/) or module it says
    try:
        import tomllib
    except ModuleNotFoundError:  # Python 3.10
        import tomli as tomllib

    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    contract = config["tool"]["importlinter"]["contracts"][0]
    assert contract["type"] == "layers"
    expected = [sorted(n.strip() for n in layer.split("|")) for layer in contract["layers"]]
    readme = _architecture_layers()
    assert [sorted(n.rstrip("/") for n in layer) for layer in readme] == expected[::-1]
    package = ROOT / "rockbench"
    for name in (n for layer in readme for n in layer):
        if name.endswith("/"):
            assert (package / name / "__init__.py").is_file(), f"{name} is not a package"
        else:
            assert (package / f"{name}.py").is_file(), f"{name} is not a module"
    # the prose above the block says where the contract lives and what checks it
    intro = (ROOT / "README.md").read_text().split("## Architecture", 1)[1].split("```", 1)[0]
    assert "pyproject.toml" in intro and "lint-imports" in intro
    named = re.findall(r"tests/\w+\.py", intro)
    assert named and all((ROOT / path).is_file() for path in named), named


def test_readme_is_an_entry_point():
    # a newcomer reads it in five minutes: the details live in docs/
    assert len((ROOT / "README.md").read_bytes()) <= 10_000


def _relative_links(path: Path) -> list[str]:
    text = path.read_text()
    links = re.findall(r"\]\(([^)\s]+)\)", text)
    return [ln.split("#", 1)[0] for ln in links
            if not re.match(r"[a-z]+:", ln) and not ln.startswith("#")]


def test_readme_and_contributing_links_resolve():
    for name in ("README.md", "CONTRIBUTING.md"):
        for link in _relative_links(ROOT / name):
            assert (ROOT / link).exists(), f"{name} links to {link}, which does not exist"


def test_every_engine_has_a_docs_page():
    from importlib.metadata import entry_points

    pages = ROOT / "docs" / "engines"
    index = (pages / "index.md").read_text()
    for ep in entry_points(group="rockbench.engines"):
        assert (pages / f"{ep.name}.md").is_file(), f"no docs/engines/{ep.name}.md"
        assert f"\n{ep.name}\n" in index, f"docs/engines/index.md does not list {ep.name}"


@pytest.mark.fast
def test_the_roof_parapet_example_files_load_and_its_code_numbers_hold():
    from rockbench.scenarios import load_scenario
    from rockbench.studies.code_check import code_check, load_site

    folder = ROOT / "docs" / "studies" / "roof-parapet"
    parapet = load_scenario(folder / "roof-parapet.toml")
    roof = code_check(parapet, load_site(folder / "roof.toml"))
    ground = code_check(parapet, load_site(folder / "ground.toml"))
    text = (ROOT / "docs" / "studies" / "roof-parapet.md").read_text()
    (lin, non) = (roof.directions[0].linear, roof.directions[0].nonlinear)
    assert roof.ec8 is not None and lin is not None and non is not None
    for number in (f"{roof.design_pga:.2f} m/s²", f"ratio {lin.ratio:.2f}",
                   f"ratio {non.ratio:.2f}", f"ratio {roof.ec8.ratio:.2f}",
                   f"capacity {non.capacity_pga:.2f} m/s²",
                   f"ratio {ground.directions[0].linear.ratio:.2f}"):
        assert number in text, number
    assert not roof.passed and not ground.passed
