"""Built-in sample surfaces, so mzc can be tried with no file to download.

Two real elevation models ship with matplotlib (a USGS DEM of the Jacksboro fault, and
a topography/bathymetry grid off the Pacific Northwest); their lat/lon steps are turned
into metres with a local equirectangular projection. ``bump`` is generated: a smooth
surface with a hole, for quick experiments.
"""

import numpy as np

from mzc.grid import ZGrid

METRES_PER_DEGREE = 111_320.0


def jacksboro():
    """The Jacksboro fault DEM (344 x 403, about 92 x 74 m cells), metres, north up."""
    from matplotlib import cbook

    data = cbook.get_sample_data("jacksboro_fault_dem.npz")
    latitude = (float(data["ymin"]) + float(data["ymax"])) / 2
    d1 = float(data["dy"]) * METRES_PER_DEGREE
    d2 = float(data["dx"]) * METRES_PER_DEGREE * np.cos(np.radians(latitude))
    z = np.flipud(data["elevation"].astype(float))  # the file's first row is the northern one
    return ZGrid(z, d1, d2, units="m")


def topobathy():
    """Topography and bathymetry (91 x 120, about 2.5 x 2.5 km cells), metres."""
    from matplotlib import cbook

    data = cbook.get_sample_data("topobathy.npz")
    latitude, longitude = data["latitude"].astype(float), data["longitude"].astype(float)
    d1 = np.diff(latitude).mean() * METRES_PER_DEGREE
    d2 = np.diff(longitude).mean() * METRES_PER_DEGREE * np.cos(np.radians(latitude.mean()))
    return ZGrid(data["topo"].astype(float), d1, d2, units="m")


def bump():
    """A generated 120 x 160 mm patch: two Gaussian bumps on a tilted plane, with a round hole."""
    y, x = np.mgrid[0:120:0.5, 0:160:0.5]
    z = (30 * np.exp(-((x - 60) ** 2 + (y - 60) ** 2) / 800) + 12 * np.exp(-((x - 115) ** 2 + (y - 50) ** 2) / 200)
         + 0.05 * x - 0.02 * y)
    z[(x - 120) ** 2 + (y - 95) ** 2 < 10**2] = np.nan
    return ZGrid(z, 0.5, 0.5, units="mm")


SAMPLES = {"jacksboro": jacksboro, "topobathy": topobathy, "bump": bump}
