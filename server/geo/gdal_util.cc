#include "server/geo/gdal_util.h"

#include <cpl_vsi.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <stdexcept>

#include "solvers/common/errors.h"

namespace gonogo::geo::internal {
namespace {

// Uploads are opened only with self-contained formats. Formats such as VRT can point at arbitrary
// server files or URLs, and header-plus-data formats (ENVI, EHdr) need sidecars an upload lacks.
const char* const kAllowedDrivers[] = {"GTiff", "GPKG", "HFA", "JP2OpenJPEG", "netCDF", nullptr};

constexpr int kMaxUploadBands = 64;

constexpr float kNoDataF = std::numeric_limits<float>::quiet_NaN();

// Rows per strip for HasAnyValidCell: at most a few MB per read.
int StripRows(int width) { return std::max(1, (1 << 20) / std::max(width, 1)); }

}  // namespace

void EnsureGdalRegistered() {
  static std::once_flag once;
  std::call_once(once, [] { GDALAllRegister(); });
}

GdalErrorScope::GdalErrorScope() : pusher_(CPLQuietErrorHandler) { CPLErrorReset(); }

std::string GdalErrorScope::LastMessage() {
  const char* message = CPLGetLastErrorMsg();
  if (message == nullptr || message[0] == '\0') return "GDAL reported no details";
  return message;
}

VsiMemFile::VsiMemFile(const std::string& bytes, const std::string& stem) {
  // A process-wide counter makes names unique across threads and calls.
  static std::atomic<uint64_t> counter{0};
  path_ = "/vsimem/gonogo_geo/" + stem + "_" + std::to_string(counter.fetch_add(1));
  // GDAL's API takes a non-const pointer; the file is only ever opened read-only and
  // bTakeOwnership=FALSE, so the caller's buffer is neither written nor freed.
  auto* data = reinterpret_cast<GByte*>(const_cast<char*>(bytes.data()));
  VSILFILE* handle = VSIFileFromMemBuffer(path_.c_str(), data, bytes.size(), FALSE);
  if (handle == nullptr) throw InputError(stem, "cannot expose the upload to GDAL");
  VSIFCloseL(handle);  // the /vsimem/ entry stays until VSIUnlink
}

VsiMemFile::~VsiMemFile() { VSIUnlink(path_.c_str()); }

OpenedRaster OpenUpload(const RasterInput& input, const std::string& field, int64_t max_cells) {
  Require(!input.bytes.empty(), field, "empty file (no bytes uploaded)");
  OpenedRaster raster;
  raster.file = std::make_unique<VsiMemFile>(input.bytes, field);
  CPLErrorReset();
  raster.dataset.reset(GDALDataset::Open(raster.file->path().c_str(),
                                         GDAL_OF_RASTER | GDAL_OF_READONLY, kAllowedDrivers));
  Require(raster.dataset != nullptr, field,
          "not a raster GDAL can read (GeoTIFF, GeoPackage, ERDAS Imagine, JPEG 2000 or netCDF "
          "expected): " +
              GdalErrorScope::LastMessage());
  GDALDataset& ds = *raster.dataset;
  raster.width = ds.GetRasterXSize();
  raster.height = ds.GetRasterYSize();
  Require(raster.width > 0 && raster.height > 0, field,
          "zero-size raster (" + std::to_string(raster.width) + " x " +
              std::to_string(raster.height) + " cells)");
  Require(ds.GetRasterCount() > 0, field,
          "raster has no bands" + std::string(ds.GetMetadata("SUBDATASETS") != nullptr
                                                  ? " (it holds several sub-datasets; upload one)"
                                                  : ""));
  // gonogo reads band 1. A few-kB TIFF can declare 65,535 bands, for each of which GDAL keeps an
  // object (about 100 MB in all, found by tests/fuzz): refused before anything reads them.
  if (ds.GetRasterCount() > kMaxUploadBands) {
    throw LimitError(field, "raster has " + std::to_string(ds.GetRasterCount()) +
                                " bands; gonogo reads band 1 of a raster of at most " +
                                std::to_string(kMaxUploadBands));
  }
  const int64_t cells = static_cast<int64_t>(raster.width) * raster.height;
  if (cells > max_cells) {
    throw LimitError(field, std::to_string(raster.width) + " x " + std::to_string(raster.height) +
                                " = " + std::to_string(cells) + " cells exceeds the limit of " +
                                std::to_string(max_cells) + " cells per input raster");
  }
  std::array<double, 6> geotransform{};
  Require(ds.GetGeoTransform(geotransform.data()) == CE_None, field,
          "no geotransform (the raster is not georeferenced)");
  Require(geotransform[1] != 0.0 && geotransform[5] != 0.0, field,
          "degenerate geotransform (zero cell size)");
  const OGRSpatialReference* crs = ds.GetSpatialRef();
  Require(crs != nullptr && !crs->IsEmpty(), field, "no CRS (coordinate reference system)");
  raster.band1 = ds.GetRasterBand(1);
  return raster;
}

std::vector<float> ReadBand1AsFloat(const OpenedRaster& raster, const std::string& field) {
  const int w = raster.width, h = raster.height;
  std::vector<float> values(static_cast<size_t>(w) * h);
  // GDAL is called before the message is built: argument evaluation order is unspecified.
  CPLErrorReset();
  const CPLErr read =
      raster.band1->RasterIO(GF_Read, 0, 0, w, h, values.data(), w, h, GDT_Float32, 0, 0, nullptr);
  Require(read == CE_None, field, "cannot read band 1: " + GdalErrorScope::LastMessage());
  // GDAL's mask band unifies the nodata value (compared in the band's own type), alpha bands and
  // internal masks; skipping it when every cell is valid saves a second decode.
  if ((raster.band1->GetMaskFlags() & GMF_ALL_VALID) == 0) {
    std::vector<uint8_t> mask(values.size());
    const CPLErr mask_read = raster.band1->GetMaskBand()->RasterIO(GF_Read, 0, 0, w, h, mask.data(),
                                                                   w, h, GDT_Byte, 0, 0, nullptr);
    Require(mask_read == CE_None, field,
            "cannot read the nodata mask: " + GdalErrorScope::LastMessage());
    for (size_t i = 0; i < values.size(); ++i) {
      if (mask[i] == 0) values[i] = kNoDataF;
    }
  }
  return values;
}

bool HasAnyValidCell(const OpenedRaster& raster) {
  const int w = raster.width, h = raster.height;
  const int strip_rows = StripRows(w);
  const bool check_mask = (raster.band1->GetMaskFlags() & GMF_ALL_VALID) == 0;
  std::vector<float> values(static_cast<size_t>(w) * strip_rows);
  std::vector<uint8_t> mask(check_mask ? values.size() : 0);
  for (int row0 = 0; row0 < h; row0 += strip_rows) {
    const int rows = std::min(strip_rows, h - row0);
    const size_t n = static_cast<size_t>(w) * rows;
    if (raster.band1->RasterIO(GF_Read, 0, row0, w, rows, values.data(), w, rows, GDT_Float32, 0, 0,
                               nullptr) != CE_None) {
      return false;
    }
    if (check_mask &&
        raster.band1->GetMaskBand()->RasterIO(GF_Read, 0, row0, w, rows, mask.data(), w, rows,
                                              GDT_Byte, 0, 0, nullptr) != CE_None) {
      return false;
    }
    for (size_t i = 0; i < n; ++i) {
      if (!std::isnan(values[i]) && (!check_mask || mask[i] != 0)) return true;
    }
  }
  return false;
}

GDALDatasetUniquePtr CreateMemDataset(const Grid& grid, int bands, GDALDataType type,
                                      const std::string& field) {
  GDALDriver* mem = GetGDALDriverManager()->GetDriverByName("MEM");
  if (mem == nullptr) throw std::runtime_error("GDAL MEM driver is missing");
  GDALDatasetUniquePtr ds(mem->Create("", grid.width, grid.height, bands, type, nullptr));
  if (ds == nullptr) {
    throw std::runtime_error("cannot create an in-memory raster of " + std::to_string(grid.width) +
                             " x " + std::to_string(grid.height) + ": " +
                             GdalErrorScope::LastMessage());
  }
  std::array<double, 6> geotransform = grid.geotransform;
  ds->SetGeoTransform(geotransform.data());
  Require(ds->SetProjection(grid.crs_wkt.c_str()) == CE_None, field,
          "grid CRS is not a valid WKT definition");
  return ds;
}

}  // namespace gonogo::geo::internal
