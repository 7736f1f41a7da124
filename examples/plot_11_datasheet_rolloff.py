"""
A datasheet system's sensitivity roll-off
=========================================

An 840 nm / 50 nm SD-OCT system described by its datasheet (camera pixels and wavelength range,
refractive index, spectrometer resolution): the roll-off measured through the simulated
spectrometer chain (cubic k-linearisation, and exact linearisation) against the closed form
``sinc²(w z) exp(-(r z)²/(2 ln 2))``. Reduced here to 512 camera pixels and 12 depths; the
pipeline target is ``results/system/rolloff.png``.
"""

from speckle.figures import system
from speckle.pipeline import default_config

config = default_config()  # the pipeline's default config, shipped with the package
sheet = {**config["system"]["datasheet"], "camera_pixels": 512}

oct_system = system.system_from_config(sheet)
print(oct_system.summary())
ds = system.rolloff_dataset(oct_system, 12, config["system"]["rolloff"]["resample"])
fig = system.plot_rolloff(ds)
