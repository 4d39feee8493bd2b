"""Small HFF-style deflection maps with no-data borders, for tests/files/lenstool.rs and
tests/cli.rs (`wslap maps --deflection`).

Published HFF lens-model maps (e.g. hlsp_frontier_model_*_x-arcsec-deflect.fits) cover their
field with NaN or with exact zeros outside the region modelled. These two 40 x 40 float32 maps
(0.5 arcsec pixels, RA---TAN / DEC--TAN, CDELT1 < 0) hold the deflection of an SIS of
theta_E = 6 arcsec at the map centre (alpha = theta_E (x, y) / r, D_ls/D_s = 1), with NaN in
the 3 columns on the East (left) edge and the 2 rows on the North (top) edge, zeros in the 4
columns on the West (right) edge and the 3 rows on the South (bottom), and one NaN pixel
inside at (column 30, row 25). Run from the repository root:
  python3 tests/data/hff_borders_reference.py   (needs numpy and astropy)
"""
import os

import numpy as np
from astropy.io import fits

HERE = os.path.dirname(os.path.abspath(__file__))
N, PIXEL, THETA_E = 40, 0.5, 6.0


def main():
    j, i = np.mgrid[0:N, 0:N]
    # Pixel centres in arcsec from the map centre (+x West = growing i, +y North = growing j).
    x = (i - (N - 1) / 2.0) * PIXEL
    y = (j - (N - 1) / 2.0) * PIXEL
    r = np.hypot(x, y)
    for name, comp in (("x", x), ("y", y)):
        data = (THETA_E * comp / r).astype(np.float32)
        data[:, :3] = np.nan  # East edge
        data[N - 2:, :] = np.nan  # North edge
        data[:, N - 4:] = 0.0  # West edge
        data[:3, :] = 0.0  # South edge
        data[25, 30] = np.nan
        hdu = fits.PrimaryHDU(data)
        h = hdu.header
        h["CTYPE1"], h["CTYPE2"] = "RA---TAN", "DEC--TAN"
        h["CUNIT1"], h["CUNIT2"] = "deg", "deg"
        h["CRPIX1"], h["CRPIX2"] = N / 2 + 0.5, N / 2 + 0.5
        h["CRVAL1"], h["CRVAL2"] = 64.0392, -24.0706
        h["CDELT1"], h["CDELT2"] = -PIXEL / 3600.0, PIXEL / 3600.0
        h["BUNIT"] = "arcsec"
        hdu.writeto(os.path.join(HERE, f"hff_borders_{name}-arcsec-deflect.fits"), overwrite=True)
    print("wrote hff_borders_{x,y}-arcsec-deflect.fits")


if __name__ == "__main__":
    main()
