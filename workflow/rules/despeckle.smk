# Speckle suppression against a known truth (results/despeckle/): the phantom and every method
# by every metric, the failure map, and split-spectrum compounding against its theory. Rules
# take the despeckle section and seed as params and the package modules their scripts import
# as inputs (see common.smk).

DESPECKLE_TARGETS = [
    f"{RESULTS}/despeckle/phantom.nc",
    f"{RESULTS}/despeckle/phantom.png",
    f"{RESULTS}/despeckle/methods.nc",
    f"{RESULTS}/despeckle/methods.png",
    f"{RESULTS}/despeckle/failure.nc",
    f"{RESULTS}/despeckle/failure.png",
    f"{RESULTS}/despeckle/frequency_compounding.nc",
]
DESPECKLE_CODE = [
    "speckle.figures.despeckle",
    "speckle.imaging.beam",  # reached through speckle.beam_scan (scan.py), not an import
    "speckle.io",
    "speckle.provenance",
]


rule despeckle_methods:
    input:
        code=package_code(*DESPECKLE_CODE),
    output:
        phantom=f"{RESULTS}/despeckle/phantom.nc",
        phantom_figure=report(
            f"{RESULTS}/despeckle/phantom.png",
            caption="../report/despeckle_phantom.rst",
            category="Speckle suppression",
            labels={
                "figure": "phantom",
                "panel": "truth, single look, best of each family",
            },
        ),
        data=f"{RESULTS}/despeckle/methods.nc",
        figure=report(
            f"{RESULTS}/despeckle/methods.png",
            caption="../report/despeckle_methods.rst",
            category="Speckle suppression",
            labels={"figure": "methods", "panel": "Pareto charts"},
        ),
    log:
        f"{RESULTS}/logs/despeckle_methods.log",
    conda:
        "../envs/speckle.yaml"
    params:
        despeckle=section_without("despeckle", "failure", "frequency_compounding"),
        seed=config["seed"],
    script:
        "../scripts/despeckle_methods.py"


rule despeckle_failure:
    input:
        code=package_code(*DESPECKLE_CODE),
    output:
        data=f"{RESULTS}/despeckle/failure.nc",
        figure=report(
            f"{RESULTS}/despeckle/failure.png",
            caption="../report/despeckle_failure.rst",
            category="Speckle suppression",
            labels={"figure": "failure map", "panel": "density, SNR, feature size"},
        ),
    log:
        f"{RESULTS}/logs/despeckle_failure.log",
    conda:
        "../envs/speckle.yaml"
    params:
        despeckle=section_without(
            "despeckle", "frequency_compounding", "physical", "filters"
        ),
        seed=config["seed"],
    script:
        "../scripts/despeckle_failure.py"


rule despeckle_frequency:
    input:
        code=package_code(*DESPECKLE_CODE),
    output:
        data=f"{RESULTS}/despeckle/frequency_compounding.nc",
    log:
        f"{RESULTS}/logs/despeckle_frequency.log",
    conda:
        "../envs/speckle.yaml"
    params:
        frequency=config["despeckle"]["frequency_compounding"],
        seed=config["seed"],
    script:
        "../scripts/despeckle_frequency.py"
