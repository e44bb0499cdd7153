#include "tests/server/geo/test_rasters.h"

#include <cpl_vsi.h>
#include <ogr_spatialref.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>

namespace gonogo::geo::fixtures {

std::string MakeGeoTiff(const RasterSpec& spec) {
  GDALAllRegister();
  static std::atomic<int> counter{0};
  const std::string path = "/vsimem/geo_test_" + std::to_string(counter++) + ".tif";
  GDALDriver* gtiff = GetGDALDriverManager()->GetDriverByName("GTiff");
  {
    GDALDatasetUniquePtr ds(
        gtiff->Create(path.c_str(), spec.width, spec.height, 1, spec.type, nullptr));
    if (ds == nullptr) throw std::runtime_error("cannot create test GeoTIFF");
    if (spec.georeferenced) {
      std::array<double, 6> gt = spec.geotransform;
      ds->SetGeoTransform(gt.data());
    }
    if (spec.epsg != 0) ds->SetProjection(WktOfEpsg(spec.epsg).c_str());
    GDALRasterBand* band = ds->GetRasterBand(1);
    if (spec.nodata) band->SetNoDataValue(*spec.nodata);
    std::vector<double> values = spec.values;
    if (values.empty()) values.assign(static_cast<size_t>(spec.width) * spec.height, spec.fill);
    if (band->RasterIO(GF_Write, 0, 0, spec.width, spec.height, values.data(), spec.width,
                       spec.height, GDT_Float64, 0, 0, nullptr) != CE_None) {
      throw std::runtime_error("cannot write test GeoTIFF");
    }
    if (spec.mask_left_half) {
      // Inside the .tif itself: only the file's bytes are uploaded, a .msk sidecar would be lost.
      CPLSetThreadLocalConfigOption("GDAL_TIFF_INTERNAL_MASK", "YES");
      ds->CreateMaskBand(GMF_PER_DATASET);
      std::vector<uint8_t> mask(values.size(), 255);
      for (int row = 0; row < spec.height; ++row) {
        for (int col = 0; col < spec.width / 2; ++col) mask[row * spec.width + col] = 0;
      }
      if (band->GetMaskBand()->RasterIO(GF_Write, 0, 0, spec.width, spec.height, mask.data(),
                                        spec.width, spec.height, GDT_Byte, 0, 0,
                                        nullptr) != CE_None) {
        throw std::runtime_error("cannot write test mask");
      }
    }
  }
  vsi_l_offset length = 0;
  GByte* data = VSIGetMemFileBuffer(path.c_str(), &length, FALSE);
  std::string bytes(reinterpret_cast<const char*>(data), static_cast<size_t>(length));
  VSIUnlink(path.c_str());
  return bytes;
}

std::string MakeRasterFile(const RasterSpec& spec, const char* driver) {
  const std::string tiff_path = "/vsimem/geo_test_convert_source.tif";
  const std::string out_path = std::string("/vsimem/geo_test_convert.") + driver;
  const std::string tiff = MakeGeoTiff(spec);
  VSILFILE* handle = VSIFileFromMemBuffer(tiff_path.c_str(),
                                          reinterpret_cast<GByte*>(const_cast<char*>(tiff.data())),
                                          tiff.size(), FALSE);
  VSIFCloseL(handle);
  {
    GDALDatasetUniquePtr src(GDALDataset::Open(tiff_path.c_str(), GDAL_OF_RASTER));
    GDALDriver* out_driver = GetGDALDriverManager()->GetDriverByName(driver);
    GDALDatasetUniquePtr out(
        out_driver->CreateCopy(out_path.c_str(), src.get(), FALSE, nullptr, nullptr, nullptr));
    if (out == nullptr) throw std::runtime_error(std::string("cannot write ") + driver);
  }
  VSIUnlink(tiff_path.c_str());
  vsi_l_offset length = 0;
  GByte* data = VSIGetMemFileBuffer(out_path.c_str(), &length, FALSE);
  std::string bytes(reinterpret_cast<const char*>(data), static_cast<size_t>(length));
  VSIUnlink(out_path.c_str());
  return bytes;
}

void FillFromCentres(RasterSpec& spec, const std::function<double(double x, double y)>& f) {
  const auto& gt = spec.geotransform;
  spec.values.resize(static_cast<size_t>(spec.width) * spec.height);
  for (int row = 0; row < spec.height; ++row) {
    for (int col = 0; col < spec.width; ++col) {
      const double x = gt[0] + (col + 0.5) * gt[1] + (row + 0.5) * gt[2];
      const double y = gt[3] + (col + 0.5) * gt[4] + (row + 0.5) * gt[5];
      spec.values[static_cast<size_t>(row) * spec.width + col] = f(x, y);
    }
  }
}

std::string WktOfEpsg(int epsg) {
  OGRSpatialReference srs;
  srs.importFromEPSG(epsg);
  char* wkt = nullptr;
  srs.exportToWkt(&wkt);
  std::string text = wkt;
  CPLFree(wkt);
  return text;
}

std::array<double, 2> Transform(int from_epsg, int to_epsg, double x, double y) {
  OGRSpatialReference from, to;
  from.importFromEPSG(from_epsg);
  to.importFromEPSG(to_epsg);
  from.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  to.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  std::unique_ptr<OGRCoordinateTransformation> ct(OGRCreateCoordinateTransformation(&from, &to));
  if (ct == nullptr || !ct->Transform(1, &x, &y)) throw std::runtime_error("transform failed");
  return {x, y};
}

TempDir::TempDir(const std::string& stem) {
  static std::atomic<int> counter{0};
  path_ = (std::filesystem::temp_directory_path() /
           (stem + "_" + std::to_string(getpid()) + "_" + std::to_string(counter++)))
              .string();
  std::filesystem::remove_all(path_);
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

int RunCommand(const std::string& command, std::string* output) {
  output->clear();
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return -1;
  char buffer[4096];
  size_t n = 0;
  while ((n = fread(buffer, 1, sizeof(buffer), pipe)) > 0) output->append(buffer, n);
  const int status = pclose(pipe);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string MakeTwoTableGeoPackage() {
  GDALAllRegister();
  const std::string path = "/vsimem/geo_test_two_tables.gpkg";
  GDALDriver* mem = GetGDALDriverManager()->GetDriverByName("MEM");
  GDALDriver* gpkg = GetGDALDriverManager()->GetDriverByName("GPKG");
  for (const char* table : {"RASTER_TABLE=a", "RASTER_TABLE=b"}) {
    GDALDatasetUniquePtr src(mem->Create("", 8, 8, 1, GDT_Byte, nullptr));
    std::array<double, 6> gt{500000.0, 10.0, 0.0, 4000000.0, 0.0, -10.0};
    src->SetGeoTransform(gt.data());
    src->SetProjection(WktOfEpsg(32617).c_str());
    const char* const options[] = {table, "APPEND_SUBDATASET=YES", nullptr};
    GDALDatasetUniquePtr out(gpkg->CreateCopy(path.c_str(), src.get(), FALSE,
                                              const_cast<char**>(options), nullptr, nullptr));
    if (out == nullptr) throw std::runtime_error("cannot create test GeoPackage");
  }
  vsi_l_offset length = 0;
  GByte* data = VSIGetMemFileBuffer(path.c_str(), &length, FALSE);
  std::string bytes(reinterpret_cast<const char*>(data), static_cast<size_t>(length));
  VSIUnlink(path.c_str());
  return bytes;
}

GDALDatasetUniquePtr OpenForCheck(const std::string& path) {
  GDALAllRegister();
  return GDALDatasetUniquePtr(
      GDALDataset::Open(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr));
}

}  // namespace gonogo::geo::fixtures
