# Elastography: strain estimators on simulated phantoms (results/elastography/).
# Each rule: NetCDF + PNG drawn from it; params = the elastography section and the seed.

ELASTOGRAPHY_TARGETS = [
    f"{RESULTS}/elastography/phantom.nc",
    f"{RESULTS}/elastography/phantom.png",
    f"{RESULTS}/elastography/inclusion.nc",
    f"{RESULTS}/elastography/inclusion.png",
    f"{RESULTS}/elastography/failure_maps.nc",
    f"{RESULTS}/elastography/failure_maps.png",
    f"{RESULTS}/elastography/speed_accuracy.nc",
    f"{RESULTS}/elastography/speed_accuracy.png",
    f"{RESULTS}/elastography/sequence.nc",
    f"{RESULTS}/elastography/sequence.png",
    f"{RESULTS}/elastography/sequence_large.nc",
    f"{RESULTS}/elastography/sequence_large.png",
]


rule elastography_phantom:
    input:
        code=package_code("speckle.figures.elastography", "speckle.io"),
    output:
        data=f"{RESULTS}/elastography/phantom.nc",
        figure=report(
            f"{RESULTS}/elastography/phantom.png",
            caption="../report/elastography_phantom.rst",
            category="Elastography",
            labels={
                "figure": "layered phantom: modulus, true strain, strain and error maps"
            },
        ),
    log:
        f"{RESULTS}/logs/elastography_phantom.log",
    conda:
        "../envs/speckle.yaml"
    threads: 1
    params:
        **section("elastography", "seed"),
    script:
        "../scripts/elastography_phantom.py"


rule elastography_inclusion:
    input:
        code=package_code("speckle.figures.elastography", "speckle.io"),
    output:
        data=f"{RESULTS}/elastography/inclusion.nc",
        figure=report(
            f"{RESULTS}/elastography/inclusion.png",
            caption="../report/elastography_inclusion.rst",
            category="Elastography",
            labels={
                "figure": "FE inclusion phantom: modulus, true strain, strain and error maps"
            },
        ),
    log:
        f"{RESULTS}/logs/elastography_inclusion.log",
    conda:
        "../envs/speckle.yaml"
    threads: 1
    params:
        **section("elastography", "seed"),
    script:
        "../scripts/elastography_inclusion.py"


# The dask section is read from the config in the script (as the sweeps do): the numbers do not
# depend on the scheduler, so changing it does not rerun the rule.
rule elastography_failure:
    input:
        code=package_code("speckle.figures.elastography", "speckle.io", "speckle.sweep"),
    output:
        data=f"{RESULTS}/elastography/failure_maps.nc",
        figure=report(
            f"{RESULTS}/elastography/failure_maps.png",
            caption="../report/elastography_failure.rst",
            category="Elastography",
            labels={"figure": "failure maps of every estimator"},
        ),
    log:
        f"{RESULTS}/logs/elastography_failure.log",
    conda:
        "../envs/speckle.yaml"
    threads: config["dask"]["n_workers"]
    params:
        **section("elastography", "seed"),
    script:
        "../scripts/elastography_failure.py"


rule elastography_speed:
    input:
        code=package_code("speckle.figures.elastography", "speckle.io"),
    output:
        data=f"{RESULTS}/elastography/speed_accuracy.nc",
        figure=report(
            f"{RESULTS}/elastography/speed_accuracy.png",
            caption="../report/elastography_speed.rst",
            category="Elastography",
            labels={"figure": "speed versus accuracy of the estimators"},
        ),
    log:
        f"{RESULTS}/logs/elastography_speed.log",
    conda:
        "../envs/speckle.yaml"
    threads: 1
    params:
        **section("elastography", "seed"),
    script:
        "../scripts/elastography_speed.py"


rule elastography_sequence:
    input:
        code=package_code("speckle.figures.elastography", "speckle.io"),
    output:
        data=f"{RESULTS}/elastography/sequence.nc",
        figure=report(
            f"{RESULTS}/elastography/sequence.png",
            caption="../report/elastography_sequence.rst",
            category="Elastography",
            labels={"figure": "compression sequence: accumulated strain"},
        ),
    log:
        f"{RESULTS}/logs/elastography_sequence.log",
    conda:
        "../envs/speckle.yaml"
    threads: 1
    params:
        **section("elastography", "seed"),
    script:
        "../scripts/elastography_sequence.py"


# The dask section is read from the config in the script (as the sweeps do): the numbers do not
# depend on the scheduler, so changing it does not rerun the rule.
rule elastography_sequence_large:
    input:
        code=package_code("speckle.figures.elastography", "speckle.io", "speckle.sweep"),
    output:
        data=f"{RESULTS}/elastography/sequence_large.nc",
        figure=report(
            f"{RESULTS}/elastography/sequence_large.png",
            caption="../report/elastography_sequence_large.rst",
            category="Elastography",
            labels={"figure": "FE inclusion compression sequence, streamed with Dask"},
        ),
    log:
        f"{RESULTS}/logs/elastography_sequence_large.log",
    conda:
        "../envs/speckle.yaml"
    threads: config["dask"]["n_workers"]
    params:
        **section("elastography", "seed"),
    script:
        "../scripts/elastography_sequence_large.py"
