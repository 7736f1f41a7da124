# Speckle in time (results/dynamics/): the phantom imaged as an angiography protocol and a
# dynamic-OCT series with its contrasts, g1 against theory, the flow-detection failure maps
# and the decorrelation calibration. Rules take the parts of the dynamics section they read
# and the seed as params, and the package modules their scripts import as inputs.

DYNAMICS_TARGETS = [
    f"{RESULTS}/dynamics/phantom.nc",
    f"{RESULTS}/dynamics/phantom.png",
    f"{RESULTS}/dynamics/g1.nc",
    f"{RESULTS}/dynamics/g1.png",
    f"{RESULTS}/dynamics/failure.nc",
    f"{RESULTS}/dynamics/failure.png",
    f"{RESULTS}/dynamics/calibration.nc",
    f"{RESULTS}/dynamics/calibration.png",
]
DYNAMICS_CODE = [
    "speckle.figures.dynamics",
    "speckle.imaging.beam",  # reached through speckle.beam_scan (scan.py), not an import
    "speckle.io",
    "speckle.provenance",
]


rule dynamics_phantom:
    input:
        code=package_code(*DYNAMICS_CODE),
    output:
        data=f"{RESULTS}/dynamics/phantom.nc",
        figure=report(
            f"{RESULTS}/dynamics/phantom.png",
            caption="../report/dynamics_phantom.rst",
            category="Speckle in time",
            labels={"figure": "phantom", "panel": "angiography and dOCT contrasts"},
        ),
    log:
        f"{RESULTS}/logs/dynamics_phantom.log",
    conda:
        "../envs/speckle.yaml"
    params:
        dynamics=section_without("dynamics", "g1", "failure", "calibration"),
        seed=config["seed"],
    script:
        "../scripts/dynamics_phantom.py"


rule dynamics_g1:
    input:
        code=package_code(*DYNAMICS_CODE),
    output:
        data=f"{RESULTS}/dynamics/g1.nc",
        figure=report(
            f"{RESULTS}/dynamics/g1.png",
            caption="../report/dynamics_g1.rst",
            category="Speckle in time",
            labels={"figure": "g1", "panel": "Brownian motion and transverse flow"},
        ),
    log:
        f"{RESULTS}/logs/dynamics_g1.log",
    conda:
        "../envs/speckle.yaml"
    params:
        dynamics=section_without("dynamics", "phantom", "failure", "calibration"),
        seed=config["seed"],
    script:
        "../scripts/dynamics_g1.py"


rule dynamics_failure:
    input:
        code=package_code(*DYNAMICS_CODE),
    output:
        data=f"{RESULTS}/dynamics/failure.nc",
        figure=report(
            f"{RESULTS}/dynamics/failure.png",
            caption="../report/dynamics_failure.rst",
            category="Speckle in time",
            labels={"figure": "failure map", "panel": "velocity, SNR, interval"},
        ),
    log:
        f"{RESULTS}/logs/dynamics_failure.log",
    conda:
        "../envs/speckle.yaml"
    params:
        dynamics=section_without("dynamics", "phantom", "g1", "calibration", "snr_db"),
        seed=config["seed"],
    script:
        "../scripts/dynamics_failure.py"


rule dynamics_calibration:
    input:
        code=package_code(*DYNAMICS_CODE),
    output:
        data=f"{RESULTS}/dynamics/calibration.nc",
        figure=report(
            f"{RESULTS}/dynamics/calibration.png",
            caption="../report/dynamics_calibration.rst",
            category="Speckle in time",
            labels={
                "figure": "calibration",
                "panel": "decorrelation against velocity",
            },
        ),
    log:
        f"{RESULTS}/logs/dynamics_calibration.log",
    conda:
        "../envs/speckle.yaml"
    params:
        dynamics=section_without("dynamics", "phantom", "g1", "failure", "snr_db"),
        seed=config["seed"],
    script:
        "../scripts/dynamics_calibration.py"
