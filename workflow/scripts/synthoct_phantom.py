"""results/synthoct/phantoms/: a self-consistency phantom and its scanner INI (thin)."""

import dataclasses
from pathlib import Path

from speckle.pipeline.runner import run
from speckle.synthoct.files import (
    ScannerConfig,
    baseline_phantom,
    write_phantom,
    write_scanner_config,
)


def main(snakemake) -> None:
    name = snakemake.wildcards.phantom
    kind, seed = snakemake.params.recipe
    config = dataclasses.replace(
        ScannerConfig(),
        scan_filename=f"Scan_{name}.png",
        scatterers_filename=Path(snakemake.output.phantom).name,
    )
    write_scanner_config(config, snakemake.output.config)
    write_phantom(baseline_phantom(kind, seed, config=config), snakemake.output.phantom)
    print(f"wrote {', '.join(snakemake.output)}")


run(main)
