"""Cache of the scattering tables: the fingerprint of an optical profile.

The cache itself (atomic .npz entries with a checksum, `TableCache`, `default_cache_directory`)
is generic and lives in `skyscatter.disk_cache`; it is re-exported here for the transport code.
"""

from __future__ import annotations

import hashlib

import numpy as np

from skyscatter.atmosphere.model import OpticalProfile
from skyscatter.disk_cache import TableCache, default_cache_directory

__all__ = ["TableCache", "default_cache_directory", "profile_fingerprint"]


def profile_fingerprint(profile: OpticalProfile) -> str:
    """SHA-256 of everything in an optical profile that changes the tables."""
    digest = hashlib.sha256()
    for array in (profile.wavelengths_nm, profile.altitudes_m, profile.density,
                  profile.extinction_per_density, profile.scattering_per_density,
                  profile.ground_albedo, profile.toa_irradiance):
        digest.update(np.ascontiguousarray(array, dtype=np.float64).tobytes())
    digest.update(repr((profile.bottom_radius_m, profile.top_radius_m,
                        profile.sun_angular_radius_rad, profile.names,
                        [repr(phase) for phase in profile.phases])).encode())
    return digest.hexdigest()
