"""Write the demo coverage map of the `earth-weather` cloud preset:
src/skyscatter/atmosphere/cloud_presets/earth-weather-coverage.png, 1024 x 512, 8-bit grey.

Made by `skyscatter.atmosphere.cloud_maps.demo_coverage_map` (zonal-mean cloud fraction of
the GEWEX Cloud Assessment and MODIS times procedural large-scale noise; sources in that
module); no data is downloaded. Run: python scripts/make_data/cloud_coverage_map.py
"""

from __future__ import annotations

from pathlib import Path

from skyscatter.atmosphere.cloud_maps import demo_coverage_map, write_coverage_png

TARGET = (Path(__file__).resolve().parents[2]
          / "src/skyscatter/atmosphere/cloud_presets/earth-weather-coverage.png")


def main() -> None:
    write_coverage_png(TARGET, demo_coverage_map(1024, 512))
    print(f"wrote {TARGET}")


if __name__ == "__main__":
    main()
