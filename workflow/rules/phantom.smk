# The phantom fit's closed loop (results/phantom/): virtual patients scanned by the drop-in
# scanner, fitted back by speckle.fit_phantom and scored as the SynthOCT challenge scores (the
# fitted phantom and the baseline's two-layer phantom against the floor), case by case on Dask.
PHANTOM_FIT = config["phantom_fit"]
PHANTOM_TARGETS = [
    f"{RESULTS}/phantom/closed_loop.nc",
    f"{RESULTS}/phantom/closed_loop.csv",
    f"{RESULTS}/phantom/closed_loop.png",
    f"{RESULTS}/phantom/scores.png",
]


rule phantom_closed_loop:
    input:
        code=package_code(
            "speckle.figures.phantom",
            "speckle.studies.phantom.batch",
            "speckle.io",
            "speckle.provenance",
        ),
    output:
        data=f"{RESULTS}/phantom/closed_loop.nc",
        table=f"{RESULTS}/phantom/closed_loop.csv",
        figure=report(
            f"{RESULTS}/phantom/closed_loop.png",
            caption="../report/phantom_closed_loop.rst",
            category="Phantom fit",
            labels={
                "figure": "closed loop",
                "panel": "pulls, boundaries, layer counts",
            },
        ),
        scores=report(
            f"{RESULTS}/phantom/scores.png",
            caption="../report/phantom_scores.rst",
            category="Phantom fit",
            labels={
                "figure": "closed loop",
                "panel": "challenge scores against the floor",
            },
        ),
    log:
        f"{RESULTS}/logs/phantom_closed_loop.log",
    conda:
        "../envs/speckle.yaml"
    params:
        phantom_fit=PHANTOM_FIT,
        dask=config["dask"],
    script:
        "../scripts/phantom_closed_loop.py"
