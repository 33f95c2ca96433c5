"""The version of frbmodel (read by setuptools, the FMUs' version check and every module that records it)."""
__version__ = "0.1.0"
