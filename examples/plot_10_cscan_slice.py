"""
A C-scan: slices of a 3-D volume
================================

A 3-D shared scene (1 scatterer per pixel x pitch x pitch voxel) imaged by a beam scanned over
a raster of lines: slices of the volume at one depth (an en-face C-scan), along x and along y.
The volume is built lazily, one Dask task per chunk of lines, each drawing only its own tiles
of the scene, so a volume is never held whole. Reduced here to 16 x 16 lines x 64 pixels; the
pipeline streams 128 x 128 lines x 512 pixels to ``results/beam/volume.nc``.
"""

from speckle.figures import beam
from speckle.pipeline import default_config

config = default_config()  # the pipeline's default config, shipped with the package
volume = {**config["beam"]["volume"], "n_lines": 16, "n_pixels": 64, "chunk": 8}
section = {**config["beam"], "volume": {**volume, "tile": [512.0, 64.0, 64.0]}}

ds = beam.volume_data(config["source"], section, config["seed"]).compute()
fig = beam.plot_volume(ds)
print(ds.field.sizes)
