"""Pure numpy/scipy physics: no xarray, no I/O."""
