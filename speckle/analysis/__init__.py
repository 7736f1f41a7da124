"""What is measured on images: statistics, correlation, tracking, strain, measured images."""

from .image_files import IMAGE_KINDS, load_image

__all__ = ["IMAGE_KINDS", "load_image"]
