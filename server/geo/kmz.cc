#include "server/geo/kmz.h"

#include <cpl_conv.h>
#include <cpl_vsi.h>
#include <gdal_priv.h>
#include <gdal_utils.h>

#include <atomic>
#include <filesystem>
#include <stdexcept>
#include <system_error>

#include "server/geo/gdal_util.h"
#include "server/geo/quicklook.h"

namespace gonogo::geo::internal {
namespace {

namespace fs = std::filesystem;

// The legend, pinned to the top-left corner of the Google Earth view at its own pixel size.
std::string ScreenOverlayKml(const std::string& title) {
  return "\t\t<ScreenOverlay>\n"
         "\t\t\t<name>Legend: " +
         title +
         "</name>\n"
         "\t\t\t<Icon><href>" +
         std::string(kKmzLegendName) +
         "</href></Icon>\n"
         "\t\t\t<overlayXY x=\"0\" y=\"1\" xunits=\"fraction\" yunits=\"fraction\"/>\n"
         "\t\t\t<screenXY x=\"10\" y=\"10\" xunits=\"pixels\" yunits=\"insetPixels\"/>\n"
         "\t\t\t<size x=\"0\" y=\"0\" xunits=\"pixels\" yunits=\"pixels\"/>\n"
         "\t\t</ScreenOverlay>\n";
}

// XML text: the title is the user's job name.
std::string EscapeXml(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// The classes as RGBA on the grid (band 4 alpha), which is what the KML tiles need: the
// KMLSUPEROVERLAY driver writes a paletted band's codes as grey levels.
GDALDatasetUniquePtr ClassesAsRgba(const Grid& grid, const std::vector<uint8_t>& go_class) {
  GDALDatasetUniquePtr rgba = CreateMemDataset(grid, 4, GDT_Byte, "grid");
  const size_t cells = go_class.size();
  std::vector<uint8_t> pixels(cells * 4);
  for (size_t i = 0; i < cells; ++i) {
    const Rgba c = ClassColour(go_class[i]);
    pixels[i * 4 + 0] = c.r;
    pixels[i * 4 + 1] = c.g;
    pixels[i * 4 + 2] = c.b;
    pixels[i * 4 + 3] = c.a;
  }
  if (rgba->RasterIO(GF_Write, 0, 0, grid.width, grid.height, pixels.data(), grid.width,
                     grid.height, GDT_Byte, 4, nullptr, 4, 4 * static_cast<GSpacing>(grid.width), 1,
                     nullptr) != CE_None) {
    throw std::runtime_error("cannot fill the KMZ image");
  }
  const GDALColorInterp interpretation[] = {GCI_RedBand, GCI_GreenBand, GCI_BlueBand,
                                            GCI_AlphaBand};
  for (int b = 0; b < 4; ++b) rgba->GetRasterBand(b + 1)->SetColorInterpretation(interpretation[b]);
  return rgba;
}

// Reprojected to EPSG:4326 with nearest neighbour: KML wants longitude / latitude, and GDAL's
// KML reader only reads back tiles with a north-up LatLonBox, which the driver writes for a
// source already in EPSG:4326 (for any other CRS it writes gx:LatLonQuad).
GDALDatasetUniquePtr ToWgs84(GDALDataset& rgba) {
  const char* const argv[] = {"-of", "MEM", "-t_srs", "EPSG:4326", "-r", "near", nullptr};
  GDALWarpAppOptions* options = GDALWarpAppOptionsNew(const_cast<char**>(argv), nullptr);
  GDALDatasetH source = GDALDataset::ToHandle(&rgba);
  GDALDatasetH warped = GDALWarp("", nullptr, 1, &source, options, nullptr);
  GDALWarpAppOptionsFree(options);
  if (warped == nullptr) {
    throw std::runtime_error("cannot reproject the KMZ image to WGS 84: " +
                             GdalErrorScope::LastMessage());
  }
  return GDALDatasetUniquePtr(GDALDataset::FromHandle(warped));
}

std::string ReadVsiFile(const std::string& path) {
  vsi_l_offset size = 0;
  GByte* data = VSIGetMemFileBuffer(path.c_str(), &size, FALSE);
  if (data == nullptr) throw std::runtime_error("GDAL wrote no " + path);
  return std::string(reinterpret_cast<const char*>(data), static_cast<size_t>(size));
}

// Adds `bytes` to the open zip as `name` (deflated).
void AddToZip(void* zip, const std::string& name, const std::string& bytes) {
  if (CPLCreateFileInZip(zip, name.c_str(), nullptr) != CE_None ||
      CPLWriteFileInZip(zip, bytes.data(), static_cast<int>(bytes.size())) != CE_None ||
      CPLCloseFileInZip(zip) != CE_None) {
    throw std::runtime_error("cannot add " + name +
                             " to the KMZ: " + GdalErrorScope::LastMessage());
  }
}

// Removes a /vsimem/ folder tree when it goes out of scope.
struct VsiMemTree {
  std::string root;
  ~VsiMemTree() { VSIRmdirRecursive(root.c_str()); }
};

}  // namespace

void WriteClassKmz(const Grid& grid, const std::vector<uint8_t>& go_class, const std::string& title,
                   const std::string& path) {
  EnsureGdalRegistered();
  GdalErrorScope gdal_errors;
  static std::atomic<uint64_t> counter{0};
  VsiMemTree tree{"/vsimem/gonogo_geo/kml_" + std::to_string(counter.fetch_add(1))};
  const std::string doc_kml = tree.root + "/doc.kml";

  // The super-overlay as a folder of KML and PNG tiles in memory.
  {
    GDALDatasetUniquePtr rgba = ClassesAsRgba(grid, go_class);
    GDALDatasetUniquePtr wgs84 = ToWgs84(*rgba);
    GDALDriver* kml = GetGDALDriverManager()->GetDriverByName("KMLSUPEROVERLAY");
    if (kml == nullptr) throw std::runtime_error("GDAL KMLSUPEROVERLAY driver is missing");
    const std::string name_option = "NAME=" + title;
    const char* const options[] = {"FORMAT=PNG", name_option.c_str(), nullptr};
    GDALDatasetUniquePtr written(kml->CreateCopy(doc_kml.c_str(), wgs84.get(), FALSE,
                                                 const_cast<char**>(options), nullptr, nullptr));
    if (written == nullptr) {
      throw std::runtime_error("cannot write the KML super-overlay: " +
                               GdalErrorScope::LastMessage());
    }
  }

  // doc.kml with the legend's screen overlay at the end of its Document.
  std::string doc = ReadVsiFile(doc_kml);
  const size_t end = doc.rfind("</Document>");
  if (end == std::string::npos) throw std::runtime_error("GDAL's doc.kml has no Document");
  doc.insert(end, ScreenOverlayKml(EscapeXml(title)));

  // The KMZ: doc.kml first (Google Earth opens the first .kml of the archive), then the tiles and
  // the legend, zipped under a temporary name and renamed.
  const std::string partial = path + ".partial";
  void* zip = CPLCreateZip(partial.c_str(), nullptr);
  if (zip == nullptr) {
    throw std::runtime_error("cannot write " + path + ": " + GdalErrorScope::LastMessage());
  }
  try {
    AddToZip(zip, "doc.kml", doc);
    char** entries = VSIReadDirRecursive(tree.root.c_str());
    for (int i = 0; entries != nullptr && entries[i] != nullptr; ++i) {
      const std::string entry = entries[i];
      VSIStatBufL stat;
      const std::string full = tree.root + "/" + entry;
      if (entry == "doc.kml" || VSIStatL(full.c_str(), &stat) != 0 || VSI_ISDIR(stat.st_mode)) {
        continue;
      }
      AddToZip(zip, entry, ReadVsiFile(full));
    }
    CSLDestroy(entries);
    AddToZip(zip, kKmzLegendName, EncodePng(RenderLegendPanel(title).get()));
  } catch (...) {
    CPLCloseZip(zip);
    std::error_code ignored;
    fs::remove(partial, ignored);
    throw;
  }
  if (CPLCloseZip(zip) != CE_None) {
    std::error_code ignored;
    fs::remove(partial, ignored);
    throw std::runtime_error("cannot write " + path + ": " + GdalErrorScope::LastMessage());
  }
  fs::rename(partial, path);
}

}  // namespace gonogo::geo::internal
