# The SynthOCT 2026 challenge (results/synthoct/): its self-consistency check (the baseline's
# uniform and two-layer phantoms, seeds A and B) scored by the challenge's maps and metrics and
# set beside the published table, and a batch of candidate phantoms through the drop-in scanner
# on Dask, as a participant's search loop runs it. With synthoct.scanner false (no scanner in
# the package yet) only the published scans are scored and the batch is not built.
SYNTHOCT = config["synthoct"]
# phantom -> (baseline generator's kind, seed name): speckle.baseline_phantom
SYNTHOCT_PHANTOMS = {
    "Exp1_Uniform_A": ["uniform", "A"],
    "Exp1_Uniform_B": ["uniform", "B"],
    "Exp2_Layers_A": ["layers", "A"],
    "Exp2_Layers_B": ["layers", "B"],
}
SYNTHOCT_TARGETS = [
    f"{RESULTS}/synthoct/self_consistency.nc",
    f"{RESULTS}/synthoct/self_consistency.csv",
    f"{RESULTS}/synthoct/self_consistency.png",
]
if SYNTHOCT["scanner"]:
    SYNTHOCT_TARGETS += [
        f"{RESULTS}/synthoct/batch.nc",
        f"{RESULTS}/synthoct/batch.png",
    ]
SYNTHOCT_CODE = [
    "speckle.figures.synthoct",
    "speckle.io",
    "speckle.provenance",
]


wildcard_constraints:
    phantom="|".join(SYNTHOCT_PHANTOMS),


if SYNTHOCT["scanner"]:

    rule synthoct_phantom:
        input:
            code=package_code("speckle.synthoct.files", "speckle.pipeline.runner"),
        output:
            config=f"{RESULTS}/synthoct/phantoms/Configuration_{{phantom}}.ini",
            phantom=f"{RESULTS}/synthoct/phantoms/Scatterers_{{phantom}}.txt",
        log:
            f"{RESULTS}/logs/synthoct_phantom_{{phantom}}.log",
        conda:
            "../envs/speckle.yaml"
        params:
            recipe=lambda wildcards: SYNTHOCT_PHANTOMS[wildcards.phantom],
        script:
            "../scripts/synthoct_phantom.py"

    rule synthoct_scan:
        input:
            config=f"{RESULTS}/synthoct/phantoms/Configuration_{{phantom}}.ini",
            phantom=f"{RESULTS}/synthoct/phantoms/Scatterers_{{phantom}}.txt",
            code=package_code("speckle.synthoct.cli"),
        output:
            f"{RESULTS}/synthoct/scans/Scan_{{phantom}}.png",
        log:
            f"{RESULTS}/logs/synthoct_scan_{{phantom}}.log",
        conda:
            "../envs/speckle.yaml"
        shell:
            # the installed command, in the official argument order, one process per phantom
            # as the challenge's orchestrator runs the exe
            "speckle-scan {input.config} {input.phantom} {output} > {log} 2>&1"


rule synthoct_self_consistency:
    input:
        scans=(
            expand(
                f"{RESULTS}/synthoct/scans/Scan_{{phantom}}.png",
                phantom=SYNTHOCT_PHANTOMS,
            )
            if SYNTHOCT["scanner"]
            else []
        ),
        code=package_code(*SYNTHOCT_CODE),
    output:
        data=f"{RESULTS}/synthoct/self_consistency.nc",
        table=f"{RESULTS}/synthoct/self_consistency.csv",
        figure=report(
            f"{RESULTS}/synthoct/self_consistency.png",
            caption="../report/synthoct_self_consistency.rst",
            category="SynthOCT challenge",
            labels={"figure": "self-consistency", "panel": "maps and metrics"},
        ),
    log:
        f"{RESULTS}/logs/synthoct_self_consistency.log",
    conda:
        "../envs/speckle.yaml"
    params:
        synthoct=section_without("synthoct", "batch"),
    script:
        "../scripts/synthoct_self_consistency.py"


rule synthoct_batch:
    input:
        code=package_code(*SYNTHOCT_CODE),
    output:
        data=f"{RESULTS}/synthoct/batch.nc",
        figure=report(
            f"{RESULTS}/synthoct/batch.png",
            caption="../report/synthoct_batch.rst",
            category="SynthOCT challenge",
            labels={"figure": "batch", "panel": "candidates' scores"},
        ),
    log:
        f"{RESULTS}/logs/synthoct_batch.log",
    conda:
        "../envs/speckle.yaml"
    params:
        synthoct=section_without("synthoct", "scanner"),
        dask=config["dask"],
    script:
        "../scripts/synthoct_batch.py"
