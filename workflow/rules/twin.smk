# The scanner's twin (results/twin/): the system fitted to a measured image, the image against
# its twin, and the strain estimators' failure maps predicted on twin image pairs. The rule
# takes the twin section and seed as params and the package modules its script imports as
# inputs (see common.smk).
TWIN_TARGETS = [
    f"{RESULTS}/twin/fit.nc",
    f"{RESULTS}/twin/compare.nc",
    f"{RESULTS}/twin/compare.png",
    f"{RESULTS}/twin/failure.nc",
    f"{RESULTS}/twin/failure.png",
]


rule twin:
    input:
        image=config["twin"]["image"],
        code=package_code("speckle.figures.twin", "speckle.io", "speckle.provenance"),
    output:
        fit=f"{RESULTS}/twin/fit.nc",
        compare=f"{RESULTS}/twin/compare.nc",
        compare_figure=report(
            f"{RESULTS}/twin/compare.png",
            caption="../report/twin_compare.rst",
            category="Scanner twin",
            labels={"figure": "twin", "panel": "measured vs twin"},
        ),
        failure=f"{RESULTS}/twin/failure.nc",
        failure_figure=report(
            f"{RESULTS}/twin/failure.png",
            caption="../report/twin_failure.rst",
            category="Scanner twin",
            labels={"figure": "twin", "panel": "predicted failure maps"},
        ),
    log:
        f"{RESULTS}/logs/twin.log",
    conda:
        "../envs/speckle.yaml"
    threads: 1
    params:
        twin=config["twin"],
        seed=config["seed"],
    script:
        "../scripts/twin.py"
