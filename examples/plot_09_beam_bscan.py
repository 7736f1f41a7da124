"""
A B-scan under a scanned Gaussian beam
======================================

One shared scene imaged by a scanned beam of waist w0 = 1 and 2 line pitches, beside the
paper's independent A-lines. A wider beam overlaps neighbouring lines: the speckle grains
widen laterally, and the lateral correlation of lines ``dx`` apart follows
``exp(-dx²/w0²)`` (drawn with the measured values). Reduced here to 64 pixels x 24 lines;
the pipeline target is ``results/beam/bscans.png``.
"""

from speckle.figures import beam
from speckle.pipeline import default_config

config = default_config()  # the pipeline's default config, shipped with the package
section = {**config["beam"], "n_pixels": 64, "waist_pitch": [1.0, 2.0], "n_lines": 24}
section.update(lags=3, chunk=12)

ds = beam.bscans_data(config["source"], section, config["seed"])
fig = beam.plot_bscans(ds)
print("lateral complex correlation, measured:", ds.lateral_complex.values.round(3))
print("theory:                                ", ds.lateral_complex_theory.values.round(3))
