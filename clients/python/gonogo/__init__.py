"""gonogo: off-road mobility maps and traction curves from gonogo-server (Python client).

The gRPC stubs (gonogo.v1) are generated from proto/ when the project is built; use the package
from the build tree: PYTHONPATH=build/python python3 -c "import gonogo".
"""
from gonogo.client import CURVE_DTYPE, Client, Curve, Job, curve_points, read_endpoint_file
from gonogo.errors import GonogoError, InputError, JobFailed
from gonogo.rasters import Raster, read_raster
from gonogo import plots

__all__ = ["Client", "Curve", "Job", "CURVE_DTYPE", "curve_points", "read_endpoint_file",
           "GonogoError", "InputError", "JobFailed", "Raster", "read_raster", "plots"]
