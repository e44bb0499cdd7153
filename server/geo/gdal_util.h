// GDAL plumbing shared by the geo sources (internal; the public API is terrain.h and products.h).
#pragma once

#include <cpl_error.h>
#include <gdal_priv.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "server/geo/terrain.h"

namespace gonogo::geo::internal {

// Registers GDAL's drivers once per process.
void EnsureGdalRegistered();

// For its lifetime, GDAL errors raised on this thread go to a quiet handler instead of stderr
// (handlers are per thread, so concurrent requests do not see each other's errors).
class GdalErrorScope {
 public:
  GdalErrorScope();
  GdalErrorScope(const GdalErrorScope&) = delete;
  GdalErrorScope& operator=(const GdalErrorScope&) = delete;

  // GDAL's last error message on this thread, or a generic text when GDAL gave none.
  static std::string LastMessage();

 private:
  CPLErrorHandlerPusher pusher_;
};

// An uploaded file exposed to GDAL as a unique /vsimem/ path without copying the bytes. The bytes
// must outlive this object, and datasets opened on the path must be closed before it is destroyed.
class VsiMemFile {
 public:
  VsiMemFile(const std::string& bytes, const std::string& stem);
  ~VsiMemFile();
  VsiMemFile(const VsiMemFile&) = delete;
  VsiMemFile& operator=(const VsiMemFile&) = delete;

  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// An uploaded raster opened read-only. Members are destroyed in reverse order, so the dataset is
// closed before its /vsimem/ file is unlinked.
struct OpenedRaster {
  std::unique_ptr<VsiMemFile> file;
  GDALDatasetUniquePtr dataset;
  GDALRasterBand* band1 = nullptr;
  int width = 0;
  int height = 0;
};

// Opens `input` and checks what every upload needs: a raster in an allowed format, non-zero size,
// at least one band, at most `max_cells` cells (LimitError), a geotransform and a CRS. Errors name
// `field`.
OpenedRaster OpenUpload(const RasterInput& input, const std::string& field, int64_t max_cells);

// Band 1 as float (width * height, row-major), NaN wherever GDAL's mask says no data (nodata value,
// alpha or internal mask) or the value itself is NaN.
std::vector<float> ReadBand1AsFloat(const OpenedRaster& raster, const std::string& field);

// True when band 1 has at least one cell with data. Reads in strips to bound memory.
bool HasAnyValidCell(const OpenedRaster& raster);

// A MEM dataset with `grid`'s size, geotransform and CRS and `bands` bands of `type`.
GDALDatasetUniquePtr CreateMemDataset(const Grid& grid, int bands, GDALDataType type,
                                      const std::string& field);

}  // namespace gonogo::geo::internal
