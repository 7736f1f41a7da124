"""End-to-end tests of the Snakemake pipeline on the reduced CI configuration.

The pipeline runs once (module fixture, ``--keep-going`` so that one failing rule does not hide
the others; ``test_pipeline_run_succeeds`` reports it) in a temporary copy of the repository,
with the copy's ``speckle`` package first on ``PYTHONPATH`` so that code tracking points at the
copy. The other tests then ask Snakemake for a dry run (``-n``, default ``--rerun-triggers``)
after changing a config section or editing a package module, and compare the planned jobs with
the rules that depend on the change. Planned jobs are read from the "Job stats" table of the
dry run.
"""

from __future__ import annotations

import ast
import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest
import yaml
from output_table import compare, load_table, summarise, tolerance
from workflow_run import CI_CONFIG, CI_RESULTS, IGNORE, snakemake

import speckle
from speckle.io import open_dataset
from speckle.provenance import module_sources

pytestmark = [pytest.mark.pipeline, pytest.mark.slow]

#: Folder holding the imported ``speckle`` package (paths in rule inputs are relative to it).
PACKAGE_ROOT = Path(speckle.__file__).resolve().parents[1]


#: The static-figure rules, the section each one reads and one value to change in it.
STATIC_CHANGES = {
    "fig1": {"fig1": {"positions": [0.0, 1.5]}},
    "fig2": {"fig2": {"densities": [0.5, 8.0]}},
    "fig5": {"fig5": {"bins": 17}},
}


def job_counts(repo: Path, *configfiles: str) -> dict[str, int]:
    """Jobs per rule a dry run would execute (``all`` excluded), from the "Job stats" table."""
    out = snakemake(repo, "-n", "--configfile", CI_CONFIG, *configfiles).stdout
    if re.search(r"Nothing to be done", out):
        return {}
    match = re.search(
        r"Job stats:\s*\n\s*job\s+count\s*\n\s*-+\s+-+\s*\n(.*?)\n\s*total\s+\d+", out, re.S
    )
    assert match, f"no job table in the dry run:\n{out}"
    rows = [line.split() for line in match.group(1).strip().splitlines()]
    return {row[0]: int(row[1]) for row in rows if row and row[0] != "all"}


def planned_jobs(repo: Path, *configfiles: str) -> set[str]:
    """Rules a dry run would execute (``all`` excluded)."""
    return set(job_counts(repo, *configfiles))


def write_config(repo: Path, name: str, overrides: dict) -> str:
    path = repo / name
    path.write_text(yaml.safe_dump(overrides))
    return name


@pytest.fixture(scope="module")
def run(tmp_path_factory, repo_root) -> tuple[Path, subprocess.CompletedProcess]:
    """A repository copy in which the whole pipeline ran (``--keep-going``) on the CI config."""
    repo = tmp_path_factory.mktemp("pipeline") / "repo"
    shutil.copytree(repo_root, repo, ignore=IGNORE)
    proc = snakemake(repo, "--cores", "2", "--keep-going", "--configfile", CI_CONFIG, check=False)
    return repo, proc


@pytest.fixture(scope="module")
def built(run) -> Path:
    """The copy, once the static figures exist (other rules may have failed: see below)."""
    repo, proc = run
    for fig in ("fig1", "fig2", "fig5"):
        assert (repo / CI_RESULTS / fig / f"{fig}.nc").is_file(), proc.stdout
    return repo


@pytest.fixture(scope="module")
def baseline(built) -> set[str]:
    """Jobs a dry run plans without any change: none, unless a rule failed in the run."""
    return planned_jobs(built)


def test_pipeline_run_succeeds(run, baseline):
    _, proc = run
    assert proc.returncode == 0, proc.stdout[-5000:]
    assert baseline == set()


def test_outputs_match_the_checked_in_table(run):
    """Every variable of every NetCDF output equals ``ci_outputs.json``: to 1e-12 relative on
    the machine the table was written on, to 1e-6 on another CPU or library versions (their
    last bits differ; ``output_table.RTOL_OTHER``). Shapes, dtypes and NaN counts exactly.

    The table was written from the CI config's outputs before the structure refactor; update it
    (``tests/pipeline/output_table.py``) only where a change of numbers is intended and explained.
    """
    repo, _ = run
    table, written_on = load_table()
    problems = compare(summarise(repo / CI_RESULTS), table, tolerance(written_on))
    assert not problems, "\n".join(problems[:40])


def test_outputs_exist_and_open(built):
    results = built / CI_RESULTS
    for fig in ("fig1", "fig2", "fig5"):
        assert (results / fig / f"{fig}.png").stat().st_size > 0
        assert (results / fig / f"{fig}.nc").is_file()
    for path in sorted(results.rglob("*.nc")):
        ds = open_dataset(path)
        assert ds.data_vars, path
    fig2 = open_dataset(results / "fig2" / "fig2.nc")
    ci = yaml.safe_load((built / CI_CONFIG).read_text())
    default = yaml.safe_load((built / "workflow/config/config.yaml").read_text())
    assert fig2.field.dtype.kind == "c"
    assert list(fig2.density.values) == default["fig2"]["densities"]
    assert fig2.sizes["x"] == ci["fig2"]["n_alines"]
    fig5 = open_dataset(results / "fig5" / "fig5.nc")
    assert list(fig5.k0_dk.values) == default["fig5"]["k0_dk"]
    # Fig. 5 images the same scatterers for each k0/delta_k: the k0-independent scene
    # attributes agree, and the histograms integrate to one.
    assert fig5.amplitude_density.sizes["bin"] == ci["fig5"]["bins"]
    widths = (fig5.bin_upper - fig5.bin_lower).values
    assert (fig5.amplitude_density * widths).sum("bin").values == pytest.approx(1.0, abs=1e-12)
    scan = open_dataset(results / "scan" / "decorrelation.nc")
    table = (built / ci["scan"]["table"]).read_text().splitlines()[1:]
    rows = {tuple(line.split("\t")) for line in table}
    assert set(scan.spectrum.values.tolist()) == {r[2] for r in rows}
    assert scan.attrs["scan_points"] == len(rows)
    fig1 = open_dataset(results / "fig1" / "fig1.nc")
    assert fig1.ascan.dtype.kind == "c" and fig1.sizes["depth"] == ci["fig1"]["n_pixels"]


@pytest.mark.parametrize("rule", sorted(STATIC_CHANGES))
def test_param_change_reruns_exactly_its_figure(built, baseline, rule):
    extra = write_config(built, f"changed_{rule}.yaml", STATIC_CHANGES[rule])
    assert planned_jobs(built, extra) - baseline == {rule}


@pytest.mark.parametrize(
    ("change", "expected", "unaffected"),
    [
        ({"source": {"k0_dk": 3.0}}, {"fig2"}, {"fig1", "fig5"}),
        ({"source": {"n_pixels": 128}}, {"fig2", "fig5"}, {"fig1"}),
        ({"seed": 7}, {"fig2", "fig5"}, {"fig1"}),
    ],
)
def test_shared_param_change_reruns_its_readers(built, baseline, change, expected, unaffected):
    """Shared sections rerun the static figures that read them (others' rules may follow)."""
    planned = planned_jobs(built, write_config(built, "changed_shared.yaml", change)) - baseline
    assert expected <= planned
    assert not unaffected & planned


@pytest.fixture(scope="module")
def rule_inputs(built) -> dict[str, set[str]]:
    """Input files of every job of a forced dry run, by rule (rules with a script only)."""
    out = snakemake(built, "-n", "-F", "--configfile", CI_CONFIG).stdout
    blocks = re.findall(r"^rule (\w+):\n((?:    .*\n)+)", out, re.M)
    assert blocks, out
    inputs = {}
    for rule, body in blocks:
        found = re.search(r"^    input: (.*)$", body, re.M)
        inputs.setdefault(rule, set()).update(found.group(1).split(", ") if found else [])
    return inputs


def test_package_edit_reruns_exactly_its_users(built, baseline, rule_inputs):
    """Editing a module reruns exactly the rules that list it (the static figures among them).

    Snakemake (>= 9.18) compares checksums of small inputs, so a bare ``touch`` is not an edit;
    the test appends a comment and restores the file afterwards. That every rule lists the
    modules its script imports is checked by the next test.
    """
    name = "speckle/figures/static.py"
    users = {rule for rule, files in rule_inputs.items() if name in files}
    assert {"fig1", "fig2", "fig5"} <= users
    module = built / name
    original = module.read_text()
    try:
        module.write_text(original + "\n# an edit\n")
        assert planned_jobs(built) == users | baseline
    finally:
        module.write_text(original)
    assert planned_jobs(built) == baseline


def _script_modules(script: Path) -> set[str]:
    """``speckle`` modules a pipeline script imports, also through the lazy API.

    (Through ``provenance._imported_modules``, the parser ``module_sources`` itself uses:
    ``speckle.ascan(...)`` after ``import speckle`` counts ``speckle.imaging.aline``.)
    """
    from speckle.provenance import _imported_modules  # private: the code-tracking parser

    found = _imported_modules(ast.parse(script.read_text()), ["speckle"])
    return {m for m in found if m.startswith("speckle")}


def test_every_imported_module_is_a_rule_input(built, rule_inputs):
    """Each rule lists (via package_code) every package source its script imports."""
    smk = "\n".join(p.read_text() for p in (built / "workflow" / "rules").glob("*.smk"))
    checked = 0
    for rule, listed in rule_inputs.items():
        found = re.search(
            rf"^rule {rule}:\n(?:(?!rule ).*\n)*?\s+\"\.\./scripts/(\S+)\"", smk, re.M
        )
        if found is None:
            continue
        script = built / "workflow" / "scripts" / found.group(1)
        modules = [m for m in _script_modules(script) if _importable(m)]
        needed = {os.path.relpath(p, PACKAGE_ROOT) for p in module_sources(*modules)}
        assert needed <= listed, f"rule {rule} misses package inputs {sorted(needed - listed)}"
        checked += 1
    assert checked >= 3


def _importable(name: str) -> bool:
    import importlib.util

    try:
        return importlib.util.find_spec(name) is not None
    except (ImportError, AttributeError):
        return False


def test_bad_config_fails_schema_validation(tmp_path, repo_root):
    repo = tmp_path / "repo"
    shutil.copytree(repo_root, repo, ignore=IGNORE)
    bad = write_config(repo, "bad.yaml", {"fig2": {"densities": [0.5, -1.0]}})
    proc = snakemake(repo, "-n", "--configfile", CI_CONFIG, bad, check=False)
    assert proc.returncode != 0
    assert "-1.0" in proc.stdout and "densities" in proc.stdout, proc.stdout
    assert re.search(r"exclusiveMinimum|less than or equal to", proc.stdout), proc.stdout


def scan_table_config(repo: Path, name: str, rows: str) -> str:
    """A config naming a scan table made of the CI table's header and ``rows``."""
    ci = yaml.safe_load((repo / CI_CONFIG).read_text())
    header = (repo / ci["scan"]["table"]).read_text().splitlines()[0]
    (repo / f"{name}.tsv").write_text(f"{header}\n{rows}")
    return write_config(repo, f"{name}.yaml", {"scan": {"table": f"{name}.tsv"}})


def test_new_scan_row_runs_only_that_row(built, baseline):
    """Paramspace: a row added to the scan table is one new job plus the stacking job."""
    ci = yaml.safe_load((built / CI_CONFIG).read_text())
    rows = "".join(
        line + "\n" for line in (built / ci["scan"]["table"]).read_text().splitlines()[1:]
    )
    more = scan_table_config(built, "scan_more", rows + "2.0\t10.0\trectangular\n")
    planned = job_counts(built, more)
    assert {k: v for k, v in planned.items() if k not in baseline} == {"scan_point": 1, "scan": 1}


def test_bad_scan_row_fails_schema_validation(built):
    bad = scan_table_config(built, "scan_bad", "-1.0\t10.0\trectangular\n")
    proc = snakemake(built, "-n", "--configfile", CI_CONFIG, bad, check=False)
    assert proc.returncode != 0
    assert "-1.0" in proc.stdout and "density" in proc.stdout, proc.stdout


def test_ci_runs_the_readme_commands(repo_root):
    """.ci/run runs every README quick-start command: the test tiers exactly, the pipeline
    and report commands on the reduced config (``--configfile`` appended), in the README's
    order (the report after the pipeline, in the fresh environment)."""
    readme = (repo_root / "README.md").read_text()
    block = re.search(r"## Quick start.*?```bash\n(.*?)```", readme, re.S)
    assert block, "README has no quick-start bash block"
    commands = [line.split("#")[0].strip() for line in block.group(1).splitlines()]
    commands = [c for c in commands if c]
    assert sum("pytest" in c for c in commands) == 2, commands  # the two tiers
    assert any("--report" in c for c in commands), commands
    ci = (repo_root / ".ci" / "run").read_text()
    lines = [line.strip() for line in ci.splitlines()]
    where = []
    for cmd in commands:
        if "pytest" in cmd:
            found = [i for i, line in enumerate(lines) if line == cmd]
        else:
            found = [i for i, line in enumerate(lines)
                     if line.startswith(f"{cmd} --configfile {CI_CONFIG}")]  # fmt: skip
        assert found, f".ci/run does not run the README's {cmd!r}"
        where.append(found[0])
    snake = [w for c, w in zip(commands, where, strict=True) if "snakemake" in c]
    assert snake == sorted(snake), "the report must follow the pipeline run"
    assert ci.splitlines()[0].startswith("#!") and "set -euo pipefail" in ci


def test_report_renders_without_docutils_messages(built):
    """``snakemake --report``: captions render (no docutils error, warning or substitution)."""
    proc = snakemake(built, "--cores", "1", "--configfile", CI_CONFIG, "--report", "report.html")
    bad = [
        line
        for line in proc.stdout.splitlines()
        if re.search(r"ERROR|WARNING|SEVERE|Undefined substitution|\(\w+/\d\)", line)
    ]
    assert not bad, proc.stdout
    assert (built / "report.html").stat().st_size > 0
