# Decorrelation scan: one job per row of the scan table (Snakemake Paramspace), so a large scan
# spreads over cluster nodes with an executor plugin; a last job stacks the rows into one
# dataset. Adding rows runs only the new rows and the stacking job.
import pandas as pd
from snakemake.utils import Paramspace

from speckle.pipeline.checks import check_scan_table

SCAN_TABLE = pd.read_csv(config["scan"]["table"], sep="\t")
validate(SCAN_TABLE, "../schemas/scan.schema.yaml")
check_scan_table(SCAN_TABLE.to_dict("records"), config["source"]["n_pixels"])
SCAN = Paramspace(SCAN_TABLE, filename_params="*", param_sep="~")
SCAN_CODE = package_code("speckle.figures.deformation", "speckle.io")


rule scan_point:
    input:
        code=SCAN_CODE,
    output:
        f"{RESULTS}/scan/points/{SCAN.wildcard_pattern}.nc",
    log:
        f"{RESULTS}/logs/scan/{SCAN.wildcard_pattern}.log",
    conda:
        "../envs/speckle.yaml"
    threads: 1
    params:
        **section("fig6", "source", "seed"),
        point=SCAN.instance,
        scan=section_without("scan", "table"),
    script:
        "../scripts/scan_point.py"


rule scan:
    input:
        points=expand(
            f"{RESULTS}/scan/points/{{point}}.nc", point=SCAN.instance_patterns
        ),
        code=SCAN_CODE,
    output:
        data=f"{RESULTS}/scan/decorrelation.nc",
        figure=report(
            f"{RESULTS}/scan/decorrelation.png",
            caption="../report/scan.rst",
            category="Deformation",
            labels={
                "figure": "scan",
                "panel": "decorrelation vs density, k0/Δk, spectrum",
            },
        ),
    log:
        f"{RESULTS}/logs/scan/combine.log",
    conda:
        "../envs/speckle.yaml"
    script:
        "../scripts/scan_combine.py"


SCAN_TARGETS = [*rules.scan.output]
