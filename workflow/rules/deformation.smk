# Fig. 6: speckle decorrelation under uniaxial strain (one rule per panel: NetCDF + PNG).
# Rules take the config sections they use as params and the package modules their scripts
# import as inputs (see common.smk), so a parameter or code change reruns exactly them.
# The strain sweeps (6b, 6c) spend much of each point in GIL-bound xarray glue, so their Dask
# threads overlap poorly; they declare one thread each so Snakemake runs them side by side.
# The dask section is read from the config in the scripts, not taken as a param: results do not
# depend on the scheduler or worker count, so changing them reruns nothing.


rule fig6a:
    input:
        code=package_code(
            "speckle.figures.deformation", "speckle.pipeline.adapters", "speckle.io"
        ),
    output:
        data=f"{RESULTS}/fig6/correlation_maps.nc",
        figure=report(
            f"{RESULTS}/fig6/fig6a.png",
            caption="../report/fig6a.rst",
            category="Deformation",
            labels={"figure": "6a", "panel": "correlation maps"},
        ),
    log:
        f"{RESULTS}/logs/fig6a.log",
    conda:
        "../envs/speckle.yaml"
    params:
        **section("fig6", "source", "seed"),
    script:
        "../scripts/fig6a.py"


rule fig6b:
    input:
        code=package_code(
            "speckle.figures.deformation", "speckle.pipeline.adapters", "speckle.io"
        ),
    output:
        data=f"{RESULTS}/fig6/correlation_vs_strain.nc",
        figure=report(
            f"{RESULTS}/fig6/fig6b.png",
            caption="../report/fig6b.rst",
            category="Deformation",
            labels={"figure": "6b", "panel": "correlation vs strain"},
        ),
    log:
        f"{RESULTS}/logs/fig6b.log",
    conda:
        "../envs/speckle.yaml"
    threads: 1
    params:
        **section("fig6", "source", "seed"),
    script:
        "../scripts/fig6_sweep.py"


rule fig6c:
    input:
        code=package_code(
            "speckle.figures.deformation", "speckle.pipeline.adapters", "speckle.io"
        ),
    output:
        data=f"{RESULTS}/fig6/non_monotonic.nc",
        figure=report(
            f"{RESULTS}/fig6/fig6c.png",
            caption="../report/fig6c.rst",
            category="Deformation",
            labels={"figure": "6c", "panel": "non-monotonic question"},
        ),
    log:
        f"{RESULTS}/logs/fig6c.log",
    conda:
        "../envs/speckle.yaml"
    threads: 1
    params:
        **section("fig6", "source", "seed"),
    script:
        "../scripts/fig6_sweep.py"


DEFORMATION_TARGETS = [*rules.fig6a.output, *rules.fig6b.output, *rules.fig6c.output]
