"""Pipeline stages: physics wrapped in labelled xarray datasets and atomic netCDF I/O."""
