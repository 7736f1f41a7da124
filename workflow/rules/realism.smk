# System effects against a measured image (results/realism/): which effects the image needs,
# and a showcase phantom. Rules take the realism section and seed as params and the package
# modules their scripts import as inputs (see common.smk).
import os

REALISM_TARGETS = [
    f"{RESULTS}/realism/realism.nc",
    f"{RESULTS}/realism/realism.png",
    f"{RESULTS}/realism/showcase.nc",
    f"{RESULTS}/realism/showcase.png",
]
REALISM_MEASURED = config["realism"]["measured"]["path"]


rule realism:
    input:
        # the configured measured image, if present (absent: the model only)
        **(
            {"measured": REALISM_MEASURED}
            if REALISM_MEASURED and os.path.isfile(REALISM_MEASURED)
            else {}
        ),
        code=package_code(
            "speckle.figures.realism",
            "speckle.analysis.measured",
            "speckle.io",
            "speckle.provenance",
        ),
    output:
        data=f"{RESULTS}/realism/realism.nc",
        figure=report(
            f"{RESULTS}/realism/realism.png",
            caption="../report/realism_compare.rst",
            category="System effects",
            labels={
                "figure": "realism",
                "panel": "measured vs model, effect by effect",
            },
        ),
    log:
        f"{RESULTS}/logs/realism.log",
    conda:
        "../envs/speckle.yaml"
    threads: 1
    params:
        realism={k: v for k, v in config["realism"].items() if k != "showcase"},
        seed=config["seed"],
    script:
        "../scripts/realism_compare.py"


rule realism_showcase:
    input:
        code=package_code("speckle.figures.realism", "speckle.io", "speckle.provenance"),
    output:
        data=f"{RESULTS}/realism/showcase.nc",
        figure=report(
            f"{RESULTS}/realism/showcase.png",
            caption="../report/realism_showcase.rst",
            category="System effects",
            labels={"figure": "realism", "panel": "showcase phantom"},
        ),
    log:
        f"{RESULTS}/logs/realism_showcase.log",
    conda:
        "../envs/speckle.yaml"
    threads: 1
    params:
        realism={"showcase": config["realism"]["showcase"]},
        seed=config["seed"],
    script:
        "../scripts/realism_showcase.py"
