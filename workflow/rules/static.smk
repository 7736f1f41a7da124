# Figs. 1, 2 and 5: static speckle (one rule per figure: NetCDF + PNG).
# Each rule takes the config sections it uses as params (a change reruns it) and the package
# modules its script imports as inputs (an edit reruns it); see common.smk.


rule fig1:
    input:
        code=package_code("speckle.figures.static", "speckle.io", "speckle.provenance"),
    output:
        data=f"{RESULTS}/fig1/fig1.nc",
        figure=report(
            f"{RESULTS}/fig1/fig1.png",
            caption="../report/fig1.rst",
            category="Static speckle",
            labels={"figure": "1", "panel": "single scatterer"},
        ),
    log:
        f"{RESULTS}/logs/fig1.log",
    conda:
        "../envs/speckle.yaml"
    params:
        fig1=config["fig1"],
        # fig1 sets its own k0/delta_k and pixel count
        source=section_without("source", "k0_dk", "n_pixels"),
    script:
        "../scripts/fig1.py"


rule fig2:
    input:
        code=package_code("speckle.figures.static", "speckle.io", "speckle.provenance"),
    output:
        data=f"{RESULTS}/fig2/fig2.nc",
        figure=report(
            f"{RESULTS}/fig2/fig2.png",
            caption="../report/fig2.rst",
            category="Static speckle",
            labels={"figure": "2", "panel": "density"},
        ),
    log:
        f"{RESULTS}/logs/fig2.log",
    conda:
        "../envs/speckle.yaml"
    threads: config["dask"]["n_workers"]
    params:
        **section("fig2", "source", "seed"),
    script:
        "../scripts/fig2.py"


rule fig5:
    input:
        code=package_code("speckle.figures.static", "speckle.io", "speckle.provenance"),
    output:
        data=f"{RESULTS}/fig5/fig5.nc",
        figure=report(
            f"{RESULTS}/fig5/fig5.png",
            caption="../report/fig5.rst",
            category="Static speckle",
            labels={"figure": "5", "panel": "k0/delta_k"},
        ),
    log:
        f"{RESULTS}/logs/fig5.log",
    conda:
        "../envs/speckle.yaml"
    threads: config["dask"]["n_workers"]
    params:
        **section("fig5", "seed"),
        source=section_without("source", "k0_dk"),  # fig5 sweeps its own k0/delta_k
    script:
        "../scripts/fig5.py"


STATIC_TARGETS = [*rules.fig1.output, *rules.fig2.output, *rules.fig5.output]
