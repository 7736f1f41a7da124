"""Pipeline scripts: ``main(snakemake)`` + ``speckle.pipeline.runner.run(main)``, all logged.

Fast checks without Snakemake (through Snakemake: ``tests/pipeline/test_scaleout.py``): every
script in ``workflow/scripts`` has the shape that makes it safe to re-import in spawned Dask
workers, and ``run`` sends output, logging, warnings, child-process output and tracebacks to
the log file and does nothing on a re-import.
"""

from __future__ import annotations

import ast
import runpy
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

SCRIPT = """
import logging, subprocess, sys, warnings
from types import SimpleNamespace
from speckle.pipeline.runner import run

snakemake = SimpleNamespace(log=[{log!r}], rule="demo")

def main(snakemake):
    print("printed")
    logging.getLogger("demo").info("logged")
    warnings.warn("warned")
    subprocess.run([sys.executable, "-c", "import sys; sys.stderr.write('child stderr\\\\n')"])
    {body}

run(main)
"""


def run_script(tmp_path: Path, body: str) -> tuple[subprocess.CompletedProcess, str]:
    log = tmp_path / "logs" / "demo.log"
    path = tmp_path / "demo.py"
    path.write_text(textwrap.dedent(SCRIPT).format(log=str(log), body=body))
    proc = subprocess.run([sys.executable, str(path)], capture_output=True, text=True)
    return proc, log.read_text()


def test_output_logging_warnings_and_children_go_to_the_log(tmp_path):
    proc, log = run_script(tmp_path, "pass")
    assert proc.returncode == 0, proc.stderr
    for text in ("printed", "INFO demo logged", "UserWarning: warned", "child stderr"):
        assert text in log, log
    assert proc.stdout == "" and proc.stderr == ""


def test_uncaught_exception_leaves_its_traceback_in_the_log(tmp_path):
    proc, log = run_script(tmp_path, "raise ValueError('bad value of n_alines')")
    assert proc.returncode != 0
    assert "rule demo failed" in log and "Traceback (most recent call last)" in log, log
    assert "ValueError: bad value of n_alines" in log, log
    assert "ValueError: bad value of n_alines" in proc.stderr  # and in Snakemake's console


def test_reimport_as_mp_main_does_nothing(tmp_path):
    """What a spawned worker does: run the script as ``__mp_main__`` without ``snakemake``."""
    path = tmp_path / "script.py"
    path.write_text(
        "from speckle.pipeline.runner import run\n\n"
        "def main(snakemake):\n    raise AssertionError('main ran')\n\nrun(main)\n"
    )
    runpy.run_path(str(path), run_name="__mp_main__")


SCRIPTS = sorted((Path(__file__).resolve().parents[2] / "workflow" / "scripts").glob("*.py"))


@pytest.mark.parametrize("script", SCRIPTS, ids=[s.name for s in SCRIPTS])
def test_script_is_main_plus_run(script):
    """Top level: docstring, imports, definitions and a last ``run(main)``; nothing else."""
    body = ast.parse(script.read_text()).body
    allowed = (ast.Import, ast.ImportFrom, ast.FunctionDef, ast.ClassDef, ast.Assign)
    for node in body[:-1]:
        docstring = isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant)
        assert docstring or isinstance(node, allowed), f"{script.name}:{node.lineno}"
        assert "snakemake" not in ast.unparse(node) or isinstance(node, ast.FunctionDef), (
            f"{script.name}:{node.lineno} uses `snakemake` outside main"
        )
    assert ast.unparse(body[-1]) == "run(main)", script.name
    mains = [n for n in body if isinstance(n, ast.FunctionDef) and n.name == "main"]
    assert len(mains) == 1 and [a.arg for a in mains[0].args.args] == ["snakemake"], script.name
