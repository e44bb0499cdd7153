"""Rasters in and out of gonogo through GDAL's Python bindings (python3-gdal)."""
import os
import uuid
from dataclasses import dataclass

import numpy as np

from gonogo.errors import InputError


@dataclass
class Raster:
    """A band with its georeferencing: `array` (rows x columns), `geotransform` (GDAL's six
    coefficients: x origin, pixel width, row rotation, y origin, column rotation, pixel height, in
    CRS units), `crs` (WKT) and `nodata` (None when there is none)."""
    array: np.ndarray
    geotransform: tuple
    crs: str
    nodata: float = None


def read_raster(path):
    """Band 1 of a GDAL-readable file as a Raster."""
    from osgeo import gdal
    gdal.UseExceptions()
    ds = gdal.Open(str(path))
    band = ds.GetRasterBand(1)
    return Raster(band.ReadAsArray(), ds.GetGeoTransform(), ds.GetProjection(), band.GetNoDataValue())


def raster_bytes(value, field):
    """The bytes of a GeoTIFF for `value`: a path (sent as it is), a Raster, or an
    (array, geotransform, crs[, nodata]) tuple written through GDAL in memory."""
    if isinstance(value, (str, os.PathLike)):
        try:
            with open(value, "rb") as f:
                return f.read()
        except OSError as e:
            raise InputError(field, f"cannot read {value}: {e.strerror}") from None
    if isinstance(value, Raster):
        value = (value.array, value.geotransform, value.crs, value.nodata)
    if not isinstance(value, (tuple, list)) or len(value) not in (3, 4):
        raise InputError(field, "give a GeoTIFF path, a Raster, or (array, geotransform, crs[, nodata])")
    array, geotransform, crs = np.asarray(value[0]), tuple(value[1]), value[2]
    nodata = value[3] if len(value) == 4 else None
    if array.ndim != 2:
        raise InputError(field, f"the array must be 2-D (rows x columns), not {array.ndim}-D")
    if len(geotransform) != 6:
        raise InputError(field, "the geotransform has six coefficients")
    from osgeo import gdal, osr
    gdal.UseExceptions()
    srs = osr.SpatialReference()
    try:
        srs.SetFromUserInput(str(crs))
    except RuntimeError as e:
        raise InputError(field, f"CRS '{crs}' is not one GDAL knows: {e}") from None
    types = {np.dtype("uint8"): gdal.GDT_Byte, np.dtype("int16"): gdal.GDT_Int16,
             np.dtype("int32"): gdal.GDT_Int32, np.dtype("uint16"): gdal.GDT_UInt16,
             np.dtype("float32"): gdal.GDT_Float32}
    gdal_type = types.get(array.dtype, gdal.GDT_Float64)
    path = f"/vsimem/gonogo-{uuid.uuid4().hex}.tif"
    ds = gdal.GetDriverByName("GTiff").Create(path, array.shape[1], array.shape[0], 1, gdal_type)
    ds.SetGeoTransform(geotransform)
    ds.SetProjection(srs.ExportToWkt())
    band = ds.GetRasterBand(1)
    if nodata is not None:
        band.SetNoDataValue(float(nodata))
    band.WriteArray(array)
    ds = None
    try:
        f = gdal.VSIFOpenL(path, "rb")
        gdal.VSIFSeekL(f, 0, 2)
        size = gdal.VSIFTellL(f)
        gdal.VSIFSeekL(f, 0, 0)
        data = gdal.VSIFReadL(1, size, f)
        gdal.VSIFCloseL(f)
    finally:
        gdal.Unlink(path)
    return bytes(data)
