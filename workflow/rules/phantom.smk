# The phantom fit's closed loop (results/phantom/): virtual patients scanned by the drop-in
# scanner, fitted back by speckle.fit_phantom and scored as the SynthOCT challenge scores (the
# fitted phantom and the baseline's two-layer phantom against the floor), case by case on Dask.
PHANTOM_FIT = config["phantom_fit"]
PHANTOM_TARGETS = [
    f"{RESULTS}/phantom/closed_loop.nc",
    f"{RESULTS}/phantom/closed_loop.csv",
    f"{RESULTS}/phantom/closed_loop.png",
    f"{RESULTS}/phantom/scores.png",
    f"{RESULTS}/phantom/failure_map.nc",
    f"{RESULTS}/phantom/failure_map.png",
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
        phantom_fit=section_without("phantom_fit", "failure_map"),
        dask=config["dask"],
    script:
        "../scripts/phantom_closed_loop.py"


rule phantom_failure_map:
    input:
        code=package_code(
            "speckle.figures.phantom",
            "speckle.studies.phantom.limits",
            "speckle.io",
            "speckle.provenance",
        ),
    output:
        data=f"{RESULTS}/phantom/failure_map.nc",
        figure=report(
            f"{RESULTS}/phantom/failure_map.png",
            caption="../report/phantom_failure_map.rst",
            category="Phantom fit",
            labels={"figure": "failure map", "panel": "thickness x contrast"},
        ),
    log:
        f"{RESULTS}/logs/phantom_failure_map.log",
    conda:
        "../envs/speckle.yaml"
    params:
        failure_map=PHANTOM_FIT["failure_map"],
        dask=config["dask"],
    script:
        "../scripts/phantom_failure_map.py"
