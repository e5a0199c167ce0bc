"""Every command-line example in the README runs (in order, in a scratch folder) and succeeds."""

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from emscatter.cli import main

README = Path(__file__).parents[1] / "README.md"


def readme_commands() -> list[str]:
    """Lines starting with ``emscatter`` in the README's ```bash blocks (continuations joined)."""
    commands = []
    for block in re.findall(r"```bash\n(.*?)```", README.read_text(), re.S):
        for line in block.replace("\\\n", " ").splitlines():
            if line.strip().startswith("emscatter "):
                commands.append(line.strip())
    return commands


def test_the_readme_has_cli_examples():
    cmds = readme_commands()
    assert len(cmds) >= 8 and any("--from" in c for c in cmds)


@pytest.mark.slow
def test_every_readme_cli_example_runs(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    for cmd in readme_commands():
        argv = shlex.split(cmd, comments=True)[1:]
        if argv[0] == "radio":
            # Sionna RT sets its own Dr.Jit variant, which fails in a process where Mitsuba already
            # set one (this pytest worker may have run render tests): a fresh interpreter, as a
            # user's shell gives it.
            env = {**os.environ, "PYTHONPATH": str(Path(__file__).parents[1] / "src")}
            proc = subprocess.run(
                [sys.executable, "-m", "emscatter.cli", *argv],
                capture_output=True,
                text=True,
                env=env,
                timeout=900,
            )
            rc, err = proc.returncode, proc.stderr
        else:
            rc = main(argv)
            err = capsys.readouterr().err
        assert rc == 0, (cmd, err)
        assert "Traceback" not in err and ": error:" not in err, (cmd, err)
    assert (tmp_path / "out" / "e.png").read_bytes()[:4] == b"\x89PNG"


def test_ci_runs_the_tests_first_then_lint_and_the_quick_demo():
    root = Path(__file__).parents[1]
    steps = [
        line.strip()
        for line in (root / ".ci" / "run").read_text().splitlines()
        if line.strip().startswith("make ")
    ]
    assert steps == ["make test", "make lint", "make demo-quick"]
    make = (root / "Makefile").read_text()
    assert re.search(r"^test: setup\n\t\$\(PY\) -m pytest -q -n 2$", make, re.M)
    assert "emscatter demo --quick" in make and "$(wildcard src tests" in make
    assert "make test" in README.read_text()  # the README's test command is CI's first step
