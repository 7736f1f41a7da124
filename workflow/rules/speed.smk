# Speed versus accuracy of the synthesis methods: the chart (A-scan and scanned-beam methods) and
# the failure map (results/speed/). Timings inside a pipeline are noisy; benchmarks/bench_ascan.py
# and benchmarks/bench_beam.py are the references for speed.

SPEED_TARGETS = [
    f"{RESULTS}/speed/speed_accuracy.nc",
    f"{RESULTS}/speed/beam_speed_accuracy.nc",
    f"{RESULTS}/speed/speed_accuracy.png",
    f"{RESULTS}/speed/failure_map.nc",
    f"{RESULTS}/speed/failure_map.png",
]


rule speed_accuracy:
    input:
        code=package_code(
            "speckle.studies.speed",
            "speckle.figures.speed",
            "speckle.pipeline.adapters",
            "speckle.io",
            "speckle.provenance",
        ),
    output:
        data=f"{RESULTS}/speed/speed_accuracy.nc",
        beam=f"{RESULTS}/speed/beam_speed_accuracy.nc",
        figure=report(
            f"{RESULTS}/speed/speed_accuracy.png",
            caption="../report/speed_accuracy.rst",
            category="Speed versus accuracy",
            labels={"figure": "speed vs accuracy"},
        ),
    log:
        f"{RESULTS}/logs/speed_accuracy.log",
    conda:
        "../envs/speckle.yaml"
    threads: 2
    params:
        **section("speed_accuracy", "source", "seed"),
    script:
        "../scripts/speed_accuracy.py"


rule failure_map:
    input:
        code=package_code(
            "speckle.studies.speed",
            "speckle.figures.speed",
            "speckle.pipeline.adapters",
            "speckle.io",
            "speckle.provenance",
        ),
    output:
        data=f"{RESULTS}/speed/failure_map.nc",
        figure=report(
            f"{RESULTS}/speed/failure_map.png",
            caption="../report/failure_map.rst",
            category="Speed versus accuracy",
            labels={"figure": "failure map"},
        ),
    log:
        f"{RESULTS}/logs/failure_map.log",
    conda:
        "../envs/speckle.yaml"
    threads: config["dask"]["n_workers"]
    params:
        **section("speed_accuracy", "source", "seed"),
    script:
        "../scripts/speed_failure_map.py"
