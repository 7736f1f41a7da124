"""The imaging system: light source, spectrometer, detection and processing chain."""
