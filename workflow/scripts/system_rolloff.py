"""Roll-off measured through the spectrometer chain against its closed form (thin)."""

from speckle.figures import system as fs
from speckle.io import to_netcdf
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run
from speckle.provenance import provenance_attrs


def main(snakemake) -> None:
    cfg = snakemake.params.system
    system = fs.system_from_config(cfg["datasheet"])
    print(system.summary())
    ds = fs.rolloff_dataset(system, cfg["rolloff"]["n_depths"], cfg["rolloff"]["resample"])
    ds.attrs.update(provenance_attrs(config={"system": cfg}), system=system.summary())
    to_netcdf(ds, snakemake.output.data)
    save(fs.plot_rolloff(ds), snakemake.output.figure)
    for name in ("measured_db", "measured_exact_db"):
        dev = abs(ds[name] - ds.analytic_db).max().item()
        print(f"max |{name} - analytic_db| = {dev:.4f} dB")
    print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")


run(main)
