# SD-OCT system and spectrometer chain (results/system/): the PSF with and without
# k-linearisation and dispersion compensation, the roll-off measured through the chain against
# its closed form, and a layered B-scan with DC, autocorrelation and mirror artefacts beside its
# processed version. Each rule writes the NetCDF file its figure is drawn from.

SYSTEM_TARGETS = [
    f"{RESULTS}/system/psf.nc",
    f"{RESULTS}/system/psf.png",
    f"{RESULTS}/system/rolloff.nc",
    f"{RESULTS}/system/rolloff.png",
    f"{RESULTS}/system/bscan.nc",
    f"{RESULTS}/system/bscan.png",
]


rule system_psf:
    input:
        code=package_code("speckle.figures.system", "speckle.io", "speckle.provenance"),
    output:
        data=f"{RESULTS}/system/psf.nc",
        figure=report(
            f"{RESULTS}/system/psf.png",
            caption="../report/system_psf.rst",
            category="SD-OCT system",
            labels={"figure": "PSF"},
        ),
    log:
        f"{RESULTS}/logs/system_psf.log",
    conda:
        "../envs/speckle.yaml"
    threads: 1
    params:
        system=section_without("system", "rolloff", "bscan"),
    script:
        "../scripts/system_psf.py"


rule system_rolloff:
    input:
        code=package_code("speckle.figures.system", "speckle.io", "speckle.provenance"),
    output:
        data=f"{RESULTS}/system/rolloff.nc",
        figure=report(
            f"{RESULTS}/system/rolloff.png",
            caption="../report/system_rolloff.rst",
            category="SD-OCT system",
            labels={"figure": "roll-off"},
        ),
    log:
        f"{RESULTS}/logs/system_rolloff.log",
    conda:
        "../envs/speckle.yaml"
    threads: 1
    params:
        system=section_without("system", "psf", "bscan", "dispersion"),
    script:
        "../scripts/system_rolloff.py"


rule system_bscan:
    input:
        code=package_code("speckle.figures.system", "speckle.io", "speckle.provenance"),
    output:
        data=f"{RESULTS}/system/bscan.nc",
        figure=report(
            f"{RESULTS}/system/bscan.png",
            caption="../report/system_bscan.rst",
            category="SD-OCT system",
            labels={"figure": "artefact B-scan"},
        ),
    log:
        f"{RESULTS}/logs/system_bscan.log",
    conda:
        "../envs/speckle.yaml"
    threads: 1
    params:
        system=section_without("system", "psf", "rolloff"),
        seed=config["seed"],
    script:
        "../scripts/system_bscan.py"
