"""The OCT system: light source and spectrum, beam, spectrometer, noise and detection."""
