# Figs. 3 and 4: speckle statistics and the measured image (one rule per figure: NetCDF + PNG).
# Each rule takes the config sections it uses as params (a change reruns it) and the package
# modules its script imports as inputs (an edit reruns it); see common.smk. The dask section
# is read from the config, not taken as params: results do not depend on the scheduler.
import os

STATISTICS_TARGETS = [
    f"{RESULTS}/fig3/fig3.nc",
    f"{RESULTS}/fig3/fig3.png",
    f"{RESULTS}/fig4/fig4.nc",
    f"{RESULTS}/fig4/fig4.png",
]
MEASURED = config["fig4"]["measured"]["path"]


rule fig3:
    input:
        code=package_code(
            "speckle.figures.histograms",
            "speckle.pipeline.adapters",
            "speckle.pipeline.outputs",
            "speckle.io",
            "speckle.provenance",
        ),
    output:
        data=f"{RESULTS}/fig3/fig3.nc",
        figure=report(
            f"{RESULTS}/fig3/fig3.png",
            caption="../report/fig3.rst",
            category="Speckle statistics",
            labels={"figure": "3", "panel": "amplitude histograms vs density"},
        ),
    log:
        f"{RESULTS}/logs/fig3.log",
    conda:
        "../envs/speckle.yaml"
    threads: config["dask"]["n_workers"]
    params:
        **section("fig3", "source", "seed"),
    script:
        "../scripts/fig3.py"


rule fig4:
    input:
        # the configured measured image, if present (absent: simulated panels only)
        **({"measured": MEASURED} if MEASURED and os.path.isfile(MEASURED) else {}),
        code=package_code(
            "speckle.figures.histograms",
            "speckle.pipeline.adapters",
            "speckle.pipeline.outputs",
            "speckle.analysis.measured",
            "speckle.io",
            "speckle.provenance",
        ),
    output:
        data=f"{RESULTS}/fig4/fig4.nc",
        figure=report(
            f"{RESULTS}/fig4/fig4.png",
            caption="../report/fig4.rst",
            category="Speckle statistics",
            labels={"figure": "4", "panel": "simulated vs measured histograms"},
        ),
    log:
        f"{RESULTS}/logs/fig4.log",
    conda:
        "../envs/speckle.yaml"
    params:
        **section("fig4", "source", "seed"),
    script:
        "../scripts/fig4.py"
