// WriteMapProducts: go/no-go class COG, speed COG and PNG quicklook.
#include "server/geo/products.h"

#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <system_error>

#include "server/geo/gdal_util.h"
#include "server/geo/geodesy.h"
#include "server/geo/quicklook.h"
#include "solvers/common/errors.h"

namespace gonogo::geo {
namespace {

namespace fs = std::filesystem;

constexpr char kLegend[] = "0=NO-GO;1=SLOW-GO;2=GO;255=no data";
constexpr char kSpeedUnits[] = "km/h";

std::string CellName(size_t index, int width) {
  return "row " + std::to_string(index / width) + " col " + std::to_string(index % width) +
         " (0-based)";
}

void CheckGrid(const Grid& grid) {
  Require(
      grid.width > 0 && grid.height > 0, "grid",
      "zero-size grid (" + std::to_string(grid.width) + " x " + std::to_string(grid.height) + ")");
  Require(grid.geotransform[1] != 0.0 && grid.geotransform[5] != 0.0, "grid",
          "degenerate geotransform (zero cell size)");
  internal::CrsMetricsFromWkt(grid.crs_wkt, "grid");
}

void CheckLayers(const Grid& grid, const std::vector<uint8_t>& go_class,
                 const std::vector<float>& speed_kmh) {
  const size_t cells = static_cast<size_t>(grid.CellCount());
  Require(go_class.size() == cells, "go_class",
          std::to_string(go_class.size()) + " values for a grid of " + std::to_string(cells) +
              " cells");
  Require(speed_kmh.size() == cells, "speed_kmh",
          std::to_string(speed_kmh.size()) + " values for a grid of " + std::to_string(cells) +
              " cells");
  for (size_t i = 0; i < cells; ++i) {
    const uint8_t c = go_class[i];
    // Messages are built only on failure: Require would build one per cell.
    if (c != kClassNoGo && c != kClassSlowGo && c != kClassGo && c != kClassNoData) {
      throw InputError("go_class", "value " + std::to_string(c) + " at " + CellName(i, grid.width) +
                                       " is not 0 (NO-GO), 1 (SLOW-GO), 2 (GO) or 255 (no data)");
    }
    const float v = speed_kmh[i];
    if (!std::isnan(v) && (std::isinf(v) || v < 0.0f)) {
      throw InputError("speed_kmh", "value at " + CellName(i, grid.width) +
                                        " is negative or infinite (NaN = no data)");
    }
  }
}

void CheckMetadata(const std::map<std::string, std::string>& metadata) {
  for (const auto& [key, value] : metadata) {
    bool key_ok = !key.empty();
    for (char c : key) {
      key_ok = key_ok && c != '=' && static_cast<unsigned char>(c) > ' ';
    }
    Require(key_ok, "metadata",
            "key '" + key + "' must be non-empty, without '=', spaces or control characters");
    Require(value.find('\0') == std::string::npos, "metadata",
            "value of '" + key + "' contains a NUL character");
  }
}

void SetMetadata(GDALDataset& ds, const std::map<std::string, std::string>& metadata) {
  for (const auto& [key, value] : metadata) ds.SetMetadataItem(key.c_str(), value.c_str());
}

// Writes `mem` as a COG at `path` through a temporary name, so a reader never sees a partial file.
void WriteCog(GDALDataset& mem, const std::string& path, const char* const* options) {
  GDALDriver* cog = GetGDALDriverManager()->GetDriverByName("COG");
  if (cog == nullptr) throw std::runtime_error("GDAL COG driver is missing");
  const std::string partial = path + ".partial";
  CPLErrorReset();
  GDALDatasetUniquePtr out(
      cog->CreateCopy(partial.c_str(), &mem, FALSE, const_cast<char**>(options), nullptr, nullptr));
  // The COG driver writes the whole file inside CreateCopy; the returned dataset is a re-open.
  const bool ok = out != nullptr;
  out.reset();
  if (!ok) {
    std::error_code ignored;
    fs::remove(partial, ignored);
    throw std::runtime_error("cannot write " + path + ": " +
                             internal::GdalErrorScope::LastMessage());
  }
  fs::rename(partial, path);
}

void WriteClassCog(const Grid& grid, const std::vector<uint8_t>& go_class,
                   const std::map<std::string, std::string>& metadata, const std::string& path) {
  GDALDatasetUniquePtr mem = internal::CreateMemDataset(grid, 1, GDT_Byte, "grid");
  GDALRasterBand* band = mem->GetRasterBand(1);
  if (band->RasterIO(GF_Write, 0, 0, grid.width, grid.height, const_cast<uint8_t*>(go_class.data()),
                     grid.width, grid.height, GDT_Byte, 0, 0, nullptr) != CE_None) {
    throw std::runtime_error("cannot fill the go/no-go raster");
  }
  band->SetNoDataValue(kClassNoData);
  // A full 256-entry palette: the three classes in colour, every other value (255 = no data)
  // transparent, so viewers show the map without any styling.
  GDALColorTable palette;
  for (int value = 0; value < 256; ++value) {
    const internal::Rgba c = internal::ClassColour(static_cast<uint8_t>(value));
    const GDALColorEntry entry{c.r, c.g, c.b, c.a};
    palette.SetColorEntry(value, &entry);
  }
  band->SetColorTable(&palette);
  band->SetColorInterpretation(GCI_PaletteIndex);
  band->SetDescription("go_class");
  SetMetadata(*mem, metadata);
  mem->SetMetadataItem("LEGEND", kLegend);
  // NEAREST overviews keep class codes intact (an average of NO-GO and GO is not SLOW-GO).
  const char* const options[] = {"COMPRESS=DEFLATE", "OVERVIEW_RESAMPLING=NEAREST", nullptr};
  WriteCog(*mem, path, options);
}

void WriteSpeedCog(const Grid& grid, const std::vector<float>& speed_kmh,
                   const std::map<std::string, std::string>& metadata, const std::string& path) {
  GDALDatasetUniquePtr mem = internal::CreateMemDataset(grid, 1, GDT_Float32, "grid");
  GDALRasterBand* band = mem->GetRasterBand(1);
  if (band->RasterIO(GF_Write, 0, 0, grid.width, grid.height, const_cast<float*>(speed_kmh.data()),
                     grid.width, grid.height, GDT_Float32, 0, 0, nullptr) != CE_None) {
    throw std::runtime_error("cannot fill the speed raster");
  }
  // NaN nodata: the in-memory convention already, and QGIS and GDAL treat it as no data.
  band->SetNoDataValue(std::nan(""));
  band->SetDescription("speed_kmh");
  band->SetUnitType(kSpeedUnits);
  SetMetadata(*mem, metadata);
  mem->SetMetadataItem("UNITS", kSpeedUnits);
  // The floating-point predictor roughly halves the size of smooth speed fields under DEFLATE;
  // AVERAGE overviews give the mean speed of a block, ignoring no data.
  const char* const options[] = {"COMPRESS=DEFLATE", "PREDICTOR=YES", "OVERVIEW_RESAMPLING=AVERAGE",
                                 nullptr};
  WriteCog(*mem, path, options);
}

// Drawn with cairo (quicklook.h), written under a temporary name and renamed.
void WriteQuicklook(const Grid& grid, const std::vector<uint8_t>& go_class,
                    const std::string& path) {
  internal::WritePngAtomically(internal::RenderQuicklook(grid.width, grid.height, go_class).get(),
                               path);
}

}  // namespace

MapProducts WriteMapProducts(const Grid& grid, const std::vector<uint8_t>& go_class,
                             const std::vector<float>& speed_kmh,
                             const std::map<std::string, std::string>& metadata,
                             const std::string& out_dir) {
  internal::EnsureGdalRegistered();
  internal::GdalErrorScope gdal_errors;
  CheckGrid(grid);
  CheckLayers(grid, go_class, speed_kmh);
  CheckMetadata(metadata);
  Require(!out_dir.empty(), "out_dir", "output directory is empty");
  fs::create_directories(out_dir);

  MapProducts products;
  products.gonogo_tif = (fs::path(out_dir) / "gonogo.tif").string();
  products.speed_tif = (fs::path(out_dir) / "speed.tif").string();
  products.quicklook_png = (fs::path(out_dir) / "quicklook.png").string();
  WriteClassCog(grid, go_class, metadata, products.gonogo_tif);
  WriteSpeedCog(grid, speed_kmh, metadata, products.speed_tif);
  WriteQuicklook(grid, go_class, products.quicklook_png);
  return products;
}

}  // namespace gonogo::geo
