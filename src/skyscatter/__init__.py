"""skyscatter: physically based simulation and rendering of planetary atmospheres.

Data flow (one module boundary per arrow, see DESIGN.md):
config (TOML) -> Atmosphere -> solver (transport) -> scene (render) -> colour -> image.
"""

from skyscatter.errors import ConfigError, InputError, SkyscatterError

__version__ = "0.1.0"
__all__ = ["ConfigError", "InputError", "SkyscatterError", "__version__"]
