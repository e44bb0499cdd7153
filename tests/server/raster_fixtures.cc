#include "raster_fixtures.h"

#include <cpl_vsi.h>
#include <gdal.h>
#include <ogr_srs_api.h>

#include <atomic>

namespace gonogo::testing {

std::string MakeTiff(const TiffSpec& spec, const std::vector<float>& values) {
  GDALAllRegister();
  static std::atomic<int> counter{0};
  const std::string path = "/vsimem/fixture_" + std::to_string(counter++) + ".tif";
  GDALDatasetH ds = GDALCreate(GDALGetDriverByName("GTiff"), path.c_str(), spec.width, spec.height,
                               1, GDT_Float32, nullptr);
  double gt[6] = {spec.origin_x, spec.cell_m, 0, spec.origin_y, 0, -spec.cell_m};
  GDALSetGeoTransform(ds, gt);
  if (spec.epsg) {
    OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
    OSRImportFromEPSG(srs, spec.epsg);
    GDALSetSpatialRef(ds, srs);
    OSRDestroySpatialReference(srs);
  }
  GDALRasterBandH band = GDALGetRasterBand(ds, 1);
  if (spec.has_nodata) GDALSetRasterNoDataValue(band, spec.nodata);
  CPLErr err = GDALRasterIO(band, GF_Write, 0, 0, spec.width, spec.height,
                            const_cast<float*>(values.data()), spec.width, spec.height, GDT_Float32,
                            0, 0);
  (void)err;
  GDALClose(ds);
  vsi_l_offset size = 0;
  GByte* data = VSIGetMemFileBuffer(path.c_str(), &size, FALSE);
  std::string bytes(reinterpret_cast<const char*>(data), static_cast<size_t>(size));
  VSIUnlink(path.c_str());
  return bytes;
}

}  // namespace gonogo::testing
