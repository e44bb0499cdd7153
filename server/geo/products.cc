// WriteMapProducts: class and speed COGs with their QGIS styles and class names, KMZ, quicklook.
#include "server/geo/products.h"

#include <gdal_rat.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <system_error>

#include "server/geo/gdal_util.h"
#include "server/geo/geodesy.h"
#include "server/geo/kmz.h"
#include "server/geo/qgis_style.h"
#include "server/geo/quicklook.h"
#include "solvers/common/errors.h"

namespace gonogo::geo {
namespace {

namespace fs = std::filesystem;

constexpr char kLegend[] = "0=NO-GO;1=SLOW-GO;2=GO;255=no data";
constexpr char kSpeedUnits[] = "km/h";
constexpr char kDefaultTitle[] = "Go / no-go map";

// IANA media types, as current catalogues write them.
constexpr char kCogMediaType[] = "image/tiff; application=geotiff; profile=cloud-optimized";
constexpr char kXmlMediaType[] = "application/xml";
constexpr char kKmzMediaType[] = "application/vnd.google-earth.kmz";
constexpr char kPngMediaType[] = "image/png";

struct ClassName {
  uint8_t value;
  const char* name;
};
constexpr ClassName kClassNames[] = {
    {kClassNoGo, "NO-GO"}, {kClassSlowGo, "SLOW-GO"}, {kClassGo, "GO"}};

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
    fs::remove(partial + ".aux.xml", ignored);
    throw std::runtime_error("cannot write " + path + ": " +
                             internal::GdalErrorScope::LastMessage());
  }
  // GDAL keeps what a TIFF cannot hold (category names, the attribute table) in a PAM sidecar
  // named after the file; it follows the file to its final name, and appears first.
  const std::string partial_sidecar = partial + ".aux.xml";
  if (fs::exists(partial_sidecar)) fs::rename(partial_sidecar, path + ".aux.xml");
  fs::rename(partial, path);
}

// Category names (GDAL's, read by QGIS as palette labels) and a thematic raster attribute table
// with value, class name and colour (read by ArcGIS), both for values 0..2.
void SetClassNames(GDALRasterBand& band) {
  CPLStringList names;
  for (const ClassName& c : kClassNames) {
    while (names.size() < c.value) names.AddString("");
    names.AddString(c.name);
  }
  band.SetCategoryNames(names.List());
  GDALDefaultRasterAttributeTable table;
  table.SetTableType(GRTT_THEMATIC);
  table.CreateColumn("Value", GFT_Integer, GFU_MinMax);
  table.CreateColumn("Class", GFT_String, GFU_Name);
  table.CreateColumn("Red", GFT_Integer, GFU_Red);
  table.CreateColumn("Green", GFT_Integer, GFU_Green);
  table.CreateColumn("Blue", GFT_Integer, GFU_Blue);
  int row = 0;
  for (const ClassName& c : kClassNames) {
    const internal::Rgba colour = internal::ClassColour(c.value);
    table.SetValue(row, 0, c.value);
    table.SetValue(row, 1, c.name);
    table.SetValue(row, 2, colour.r);
    table.SetValue(row, 3, colour.g);
    table.SetValue(row, 4, colour.b);
    ++row;
  }
  band.SetDefaultRAT(&table);
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
  SetClassNames(*band);
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
                    const std::string& title, const std::string& path) {
  internal::WritePngAtomically(internal::RenderQuicklook(grid, go_class, title).get(), path);
}

void WriteTextAtomically(const std::string& text, const std::string& path) {
  const std::string partial = path + ".partial";
  {
    std::ofstream out(partial, std::ios::binary | std::ios::trunc);
    out << text;
    if (!out.flush()) {
      std::error_code ignored;
      fs::remove(partial, ignored);
      throw std::runtime_error("cannot write " + path);
    }
  }
  fs::rename(partial, path);
}

double HighestSpeedKmh(const std::vector<float>& speed_kmh) {
  double highest = 0.0;
  for (const float v : speed_kmh) {
    if (!std::isnan(v)) highest = std::max(highest, static_cast<double>(v));
  }
  return highest;
}

}  // namespace

MapProducts WriteMapProducts(const Grid& grid, const std::vector<uint8_t>& go_class,
                             const std::vector<float>& speed_kmh, const MapDescription& description,
                             const std::string& out_dir) {
  internal::EnsureGdalRegistered();
  internal::GdalErrorScope gdal_errors;
  CheckGrid(grid);
  CheckLayers(grid, go_class, speed_kmh);
  CheckMetadata(description.metadata);
  Require(!out_dir.empty(), "out_dir", "output directory is empty");
  fs::create_directories(out_dir);

  const std::string title = description.title.empty() ? kDefaultTitle : description.title;
  const fs::path dir(out_dir);
  MapProducts p;
  p.gonogo_tif = (dir / "gonogo.tif").string();
  p.gonogo_aux_xml = p.gonogo_tif + ".aux.xml";
  p.gonogo_qml = (dir / "gonogo.qml").string();
  p.speed_tif = (dir / "speed.tif").string();
  p.speed_qml = (dir / "speed.qml").string();
  p.kmz = (dir / "gonogo.kmz").string();
  p.quicklook_png = (dir / "quicklook.png").string();
  // Styles first: a reader that sees a raster finds its style already beside it.
  WriteTextAtomically(internal::ClassStyleQml(), p.gonogo_qml);
  WriteTextAtomically(
      internal::SpeedStyleQml(internal::SpeedRampMaxKmh(HighestSpeedKmh(speed_kmh))), p.speed_qml);
  WriteClassCog(grid, go_class, description.metadata, p.gonogo_tif);
  if (!fs::exists(p.gonogo_aux_xml)) {
    throw std::runtime_error("GDAL wrote no " + p.gonogo_aux_xml + " with the class names");
  }
  WriteSpeedCog(grid, speed_kmh, description.metadata, p.speed_tif);
  internal::WriteClassKmz(grid, go_class, title, p.kmz);
  WriteQuicklook(grid, go_class, title, p.quicklook_png);
  p.files = {
      {"gonogo.tif", kCogMediaType, {"data"}, "Go / no-go class: 0 NO-GO, 1 SLOW-GO, 2 GO"},
      {"gonogo.tif.aux.xml", kXmlMediaType, {"metadata"}, "Class names of gonogo.tif (GDAL PAM)"},
      {"gonogo.qml", kXmlMediaType, {"metadata"}, "QGIS style of gonogo.tif"},
      {"speed.tif", kCogMediaType, {"data"}, "Speed made good, km/h"},
      {"speed.qml", kXmlMediaType, {"metadata"}, "QGIS style of speed.tif"},
      {"gonogo.kmz", kKmzMediaType, {"visual"}, "Go / no-go classes for Google Earth"},
      {"quicklook.png", kPngMediaType, {"overview"}, title},
  };
  return p;
}

}  // namespace gonogo::geo
