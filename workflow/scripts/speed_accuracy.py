"""Speed-versus-accuracy chart of the A-scan and scanned-beam synthesis methods (thin: config ->
package -> files)."""

from speckle.figures.speed import plot_speed_accuracy
from speckle.io import to_netcdf
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run
from speckle.provenance import provenance_attrs
from speckle.studies.speed import beam_speed_accuracy, speed_accuracy


def main(snakemake) -> None:
    cfg, source, seed = (
        snakemake.params.speed_accuracy,
        snakemake.params.source,
        snakemake.params.seed,
    )
    common = dict(
        pixel_size=source["pixel_size"],
        k0_dk=source["k0_dk"],
        shape=cfg["shape"],
        fwhm_fraction=cfg["fwhm_fraction"],
        seed=seed,
        repeat=cfg["repeat"],
    )
    ds = speed_accuracy(cfg["sizes"], cfg["methods"], cfg["tols"], **common)
    beam = beam_speed_accuracy(cfg["beam"]["sizes"], cfg["beam"]["methods"], cfg["tols"], **common)
    prov = provenance_attrs(config={"speed_accuracy": cfg, "source": source}, seed=seed)
    for out, path in ((ds, snakemake.output.data), (beam, snakemake.output.beam)):
        out.attrs.update(prov)
        to_netcdf(out, path)
    save(plot_speed_accuracy(ds, beam), snakemake.output.figure)
    print(f"wrote {snakemake.output.data}, {snakemake.output.beam} and {snakemake.output.figure}")


run(main)
