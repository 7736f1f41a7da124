"""A successful run tells the newcomer where the figures are and the next command.

The Snakefile's ``onsuccess`` hook prints the results folder of the run's config and the report
command with the run's ``--configfile`` options; a dry run prints nothing of it. One cheap target
(Fig. 1 on the reduced configuration) in a temporary copy of the repository.
"""

from __future__ import annotations

import shutil

import pytest
from workflow_run import CI_CONFIG, CI_RESULTS, IGNORE, snakemake

pytestmark = [pytest.mark.pipeline, pytest.mark.slow]

NEXT = f"snakemake --report report.html --configfile {CI_CONFIG}"


def test_a_run_names_the_results_folder_and_the_report_command(tmp_path, repo_root):
    repo = tmp_path / "repo"
    shutil.copytree(repo_root, repo, ignore=IGNORE)
    target = f"{CI_RESULTS}/fig1/fig1.png"
    dry = snakemake(repo, target, "-n", "--configfile", CI_CONFIG)
    assert NEXT not in dry.stdout, dry.stdout[-3000:]
    proc = snakemake(repo, target, "--cores", "1", "--configfile", CI_CONFIG)
    assert (repo / target).stat().st_size > 0
    assert f"are in {CI_RESULTS}/," in proc.stdout, proc.stdout[-3000:]
    assert NEXT in proc.stdout, proc.stdout[-3000:]
