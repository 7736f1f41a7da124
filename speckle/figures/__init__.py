"""Figure functions: each takes the NetCDF dataset a pipeline rule wrote and returns a Figure."""
