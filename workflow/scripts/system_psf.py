"""PSF at several depths with and without k-linearisation and compensation (thin)."""

from speckle.figures import system as fs
from speckle.io import to_netcdf
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run
from speckle.provenance import provenance_attrs


def main(snakemake) -> None:
    cfg = snakemake.params.system
    system = fs.system_from_config(cfg["datasheet"])
    print(system.summary())
    ds = fs.psf_dataset(system, cfg["psf"]["depths"], fs.dispersion_from_config(cfg["dispersion"]))
    ds.attrs.update(provenance_attrs(config={"system": cfg}), system=system.summary())
    to_netcdf(ds, snakemake.output.data)
    save(fs.plot_psf(ds), snakemake.output.figure)
    print(ds.width.to_pandas())
    print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")


run(main)
