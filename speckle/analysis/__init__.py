"""What is measured on images: statistics, correlation, tracking, strain, measured images."""
