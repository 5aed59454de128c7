"""PC-side tools for the IPMSM sensorless motor drive."""

__version__ = "0.1.0"
