"""hcomc: cooperative on-ramp merging control in mixed traffic on two-lane highways.

The package implements the HCOMC method (Wang et al., arXiv:2507.11621) on top of a
struct-of-arrays microscopic traffic simulator. Importing it has no side effects.
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("hcomc")
except PackageNotFoundError:  # pragma: no cover - running from a source tree without install
    __version__ = "0.0.0+unknown"

__all__ = ["__version__"]
