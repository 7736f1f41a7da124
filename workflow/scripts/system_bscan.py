"""Layered B-scan with DC, autocorrelation and mirror artefacts, raw and processed (thin)."""

from speckle.figures import system as fs
from speckle.io import to_netcdf
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run
from speckle.provenance import provenance_attrs


def main(snakemake) -> None:
    cfg, seed = snakemake.params.system, snakemake.params.seed
    system = fs.system_from_config(cfg["datasheet"])
    print(system.summary())
    ds = fs.artefact_bscan(
        system,
        **cfg["bscan"] | {"seed": seed},
        dispersion=fs.dispersion_from_config(cfg["dispersion"]),
    )
    ds.attrs.update(provenance_attrs(config={"system": cfg}, seed=seed), system=system.summary())
    to_netcdf(ds, snakemake.output.data)
    save(fs.plot_artefact_bscan(ds), snakemake.output.figure)
    print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")


run(main)
