"""g2tom: the Greenwood²–Tripp oxidized model (G²TOM) pipeline."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("g2tom")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.0.0+unknown"
