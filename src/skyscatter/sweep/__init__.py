"""Sweeps: one model run for every combination of config values, geometries and wavelengths.

A sweep (`plan.SweepPlan`) is the product of config axes (dotted keys of
`atmosphere.config_overrides`, e.g. `constituent[2].optics.optical_depth` x
`planet.ground_albedo`) and the geometry: sun zenith x view zenith x azimuth relative to the
sun, at monochromatic wavelengths. It runs on Dask (`dask_cluster`): one task builds the solver
of each distinct atmosphere (its tables, once), and one task per chunk (one atmosphere at one
sun zenith: every view direction and wavelength) computes the radiance and surface irradiance
from that solver (`render.radiance_grid`, the same arrays as `api.sky_radiance_rows`). Finished
chunks go to a chunk store beside the output (`store.ChunkStore`), so an interrupted sweep
resumes where it stopped; `assemble` makes the labelled arrays of the whole sweep from the
store. `docs/sweep.md` describes the output layout and how to run on a cluster.

Modules: `plan` (the grid, the chunks, the fingerprint), `tasks` (what workers run), `store`
(finished chunks on disk), `run` (the Dask scheduling), `assemble` (the arrays of the result).
"""
