"""skyscatter: physically based simulation and rendering of planetary atmospheres.

Data flow (one module boundary per arrow, see docs/architecture.md):
config (TOML) -> Atmosphere -> solver (transport) -> scene (render) -> colour -> image.
"""

from pathlib import Path

from skyscatter.blas_threads import let_idle_threads_sleep
from skyscatter.errors import ConfigError, InputError, SkyscatterError
from skyscatter.jit_cache import use_writable_cache_folder

__version__ = "0.1.0"
__all__ = ["ConfigError", "InputError", "SkyscatterError", "__version__"]

let_idle_threads_sleep()  # before numpy loads OpenBLAS (none of the above imports numpy)
use_writable_cache_folder(Path(__file__).parent)  # before any numba kernel is imported
