# speckle: reproduce the figures of Zaitsev et al., "A model for simulating speckle-pattern
# evolution based on close to reality procedures used in spectral-domain OCT".
# Thin entry point: rules live in workflow/rules/*.smk, science in the speckle package.
import os
from pathlib import Path

import yaml
from snakemake.utils import min_version, validate

from speckle.pipeline.checks import check_config
from speckle.pipeline.config_keys import rename_retired_keys

min_version("9.0")


configfile: "workflow/config/config.yaml"


# retired keys (fragment.aline -> fragment.x) read under their new names, warning; both refused
rename_retired_keys(config, given=workflow.overwrite_configfiles)
validate(config, "workflow/schemas/config.schema.yaml")
# what the schema cannot say (16.0 as integer, .inf, cross-field rules, memory): before any job
check_config(
    config,
    yaml.safe_load(
        Path(workflow.basedir, "workflow/schemas/config.schema.yaml").read_text()
    ),
)


report: "workflow/report/workflow.rst"


include: "workflow/rules/common.smk"
include: "workflow/rules/static.smk"
include: "workflow/rules/statistics.smk"
include: "workflow/rules/deformation.smk"
include: "workflow/rules/scan.smk"
include: "workflow/rules/speed.smk"
include: "workflow/rules/elastography.smk"
include: "workflow/rules/system.smk"
include: "workflow/rules/realism.smk"
include: "workflow/rules/beam.smk"
include: "workflow/rules/despeckle.smk"
include: "workflow/rules/twin.smk"
include: "workflow/rules/synthoct.smk"
include: "workflow/rules/dynamics.smk"
include: "workflow/rules/phantom_real.smk"
include: "workflow/rules/phantom.smk"


rule all:
    default_target: True
    input:
        STATIC_TARGETS
        + STATISTICS_TARGETS
        + DEFORMATION_TARGETS
        + SCAN_TARGETS
        + SPEED_TARGETS
        + ELASTOGRAPHY_TARGETS
        + SYSTEM_TARGETS
        + REALISM_TARGETS
        + BEAM_TARGETS
        + DESPECKLE_TARGETS
        + TWIN_TARGETS
        + SYNTHOCT_TARGETS
        + DYNAMICS_TARGETS
        + PHANTOM_REAL_TARGETS
        + PHANTOM_TARGETS,


onsuccess:
    # a newcomer's next step; spawned cluster jobs run with --no-hooks, dry runs skip it
    again = "".join(
        f" --configfile {os.path.relpath(c)}"
        for c in workflow.overwrite_configfiles
    )
    print(
        f"\nspeckle: the figures (PNG) and the NetCDF data each is drawn from are in "
        f"{RESULTS}/, one folder per figure family (README.md, 'What the pipeline writes').\n"
        f"Next, an HTML report of every figure with its caption (plus any --config of this run):\n"
        f"    snakemake --report report.html{again}\n"
    )
