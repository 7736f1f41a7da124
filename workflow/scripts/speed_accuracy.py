"""Speed-versus-accuracy chart of the synthesis methods (thin: config -> package -> files)."""

from speckle._workflow import run
from speckle.figures._style import save
from speckle.figures.speed import speed_accuracy_figure
from speckle.imaging.speed import speed_accuracy
from speckle.io import to_netcdf
from speckle.provenance import provenance_attrs


def main(snakemake) -> None:
    cfg, source, seed = (
        snakemake.params.speed_accuracy,
        snakemake.params.source,
        snakemake.params.seed,
    )
    ds = speed_accuracy(
        cfg["sizes"],
        cfg["methods"],
        cfg["tols"],
        pixel_size=source["pixel_size"],
        k0_dk=source["k0_dk"],
        shape=cfg["shape"],
        fwhm_fraction=cfg["fwhm_fraction"],
        seed=seed,
        repeat=cfg["repeat"],
    )
    ds.attrs.update(provenance_attrs(config={"speed_accuracy": cfg, "source": source}, seed=seed))
    to_netcdf(ds, snakemake.output.data)
    save(speed_accuracy_figure(ds), snakemake.output.figure)
    print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")


run(main)
