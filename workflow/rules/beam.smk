# Scanned Gaussian beam over shared scenes (results/beam/): B-scans for several waist/pitch
# ratios beside the paper's independent A-lines, correlation versus strain under the beam, and
# a 3-D volume streamed by tiles to a chunked NetCDF file with its orthogonal slices.

BEAM_CODE = package_code(
    "speckle.figures.beam",
    "speckle.pipeline.adapters",
    "speckle.io",
    "speckle.provenance",
)


rule beam_bscans:
    input:
        code=BEAM_CODE,
    output:
        data=f"{RESULTS}/beam/bscans.nc",
        figure=report(
            f"{RESULTS}/beam/bscans.png",
            caption="../report/beam_bscans.rst",
            category="Scanned beam",
            labels={"figure": "B-scans and correlation"},
        ),
    log:
        f"{RESULTS}/logs/beam_bscans.log",
    conda:
        "../envs/speckle.yaml"
    threads: 1
    params:
        **section("source", "seed"),
        beam=section_without("beam", "strain", "volume"),
    script:
        "../scripts/beam_bscans.py"


rule beam_strain:
    input:
        code=BEAM_CODE,
    output:
        data=f"{RESULTS}/beam/correlation_vs_strain.nc",
        figure=report(
            f"{RESULTS}/beam/correlation_vs_strain.png",
            caption="../report/beam_strain.rst",
            category="Scanned beam",
            labels={"figure": "correlation vs strain under the beam"},
        ),
    log:
        f"{RESULTS}/logs/beam_strain.log",
    conda:
        "../envs/speckle.yaml"
    threads: 1
    params:
        **section("source", "seed"),
        beam=section_without("beam", "waist_pitch", "n_lines", "lags", "volume"),
    script:
        "../scripts/beam_strain.py"


rule beam_volume:
    input:
        code=BEAM_CODE,
    output:
        data=f"{RESULTS}/beam/volume.nc",
        figure=report(
            f"{RESULTS}/beam/volume_slices.png",
            caption="../report/beam_volume.rst",
            category="Scanned beam",
            labels={"figure": "streamed volume, orthogonal slices"},
        ),
    log:
        f"{RESULTS}/logs/beam_volume.log",
    conda:
        "../envs/speckle.yaml"
    threads: 2
    params:
        **section("source", "seed"),
        beam=section_without(
            "beam",
            "waist_pitch",
            "n_lines",
            "lags",
            "strain",
            "density",
            "chunk",
            "method",
            "tol",
        ),
    script:
        "../scripts/beam_volume.py"


BEAM_TARGETS = [
    *rules.beam_bscans.output,
    *rules.beam_strain.output,
    *rules.beam_volume.output,
]
