"""The codecs that compress a z-grid: the thesis's per-row codecs (rows/) and the 2D wavelet (dwt2d/)."""
