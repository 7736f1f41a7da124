"""results/phantom/real/<name>: a phantom fitted to a measured image, its scans, scores (thin)."""

from speckle.figures import phantom_real
from speckle.io import to_netcdf
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run
from speckle.provenance import provenance_attrs


def main(snakemake) -> None:
    cfg = dict(snakemake.params.section)
    image = dict(cfg.pop("image"))
    image["image"] = snakemake.input.image
    ds = phantom_real.phantom_real_data(
        image,
        seeds=cfg["seeds"],
        per_cell=cfg["per_cell"],
        max_layers=cfg["max_layers"],
        variant=cfg["variant"],
    )
    ds.attrs.update(provenance_attrs(config={"phantom_real": snakemake.params.section}))
    to_netcdf(ds, snakemake.output.data)
    save(phantom_real.plot_phantom_real(ds), snakemake.output.figure)
    print(ds[["top", "attenuation", "attenuation_se", "rho_e"]].to_dataframe())
    for k in ("MS-SSIM", "SSIM"):
        print(k, "gap (measured vs fitted - floor):", ds[f"{k}_gap"].round(3).values.tolist())
    print(f"profile_residual_rms = {float(ds.profile_residual_rms):.3g} dB")
    for k in ("log_variance", "axial", "lateral", "lateral_spread"):
        print(", ".join(f"{k}_{n} = {float(ds[f'{k}_{n}']):.4g}" for n in ("measured", "fitted")))


run(main)
