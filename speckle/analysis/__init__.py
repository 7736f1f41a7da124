"""What is measured on images: statistics, correlation, tracking, strain, measured images."""

from .image_files import IMAGE_KINDS, load_image
from .twin import SystemFit, fit_system

__all__ = ["IMAGE_KINDS", "SystemFit", "fit_system", "load_image"]
