"""Forming images: the paper's Eq. 4 (``aline``), its fast methods, the beam, B-scans."""
