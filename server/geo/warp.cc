#include "server/geo/warp.h"

#include <cpl_conv.h>
#include <gdal_alg.h>
#include <gdalwarper.h>

#include <cmath>
#include <limits>
#include <type_traits>

#include "solvers/common/errors.h"

namespace gonogo::geo::internal {
namespace {

// GDAL's usual tolerance for the approximate transformer, in output pixels: exact enough for
// resampling and several times faster than transforming every pixel.
constexpr double kApproxMaxErrorPixels = 0.125;

// Frees the GDAL warp objects on every exit path.
struct WarpResources {
  void* transformer = nullptr;
  void* approx_transformer = nullptr;
  GDALWarpOptions* options = nullptr;
  ~WarpResources() {
    if (options != nullptr) GDALDestroyWarpOptions(options);
    if (approx_transformer != nullptr) GDALDestroyApproxTransformer(approx_transformer);
    if (transformer != nullptr) GDALDestroyGenImgProjTransformer(transformer);
  }
};

// Size of a source cell measured in output cells (geometric mean of both axes) at the centre of the
// source; 0 when the centre cannot be transformed.
double SourceCellsInOutputCells(void* transformer, const OpenedRaster& source) {
  const double cx = 0.5 * source.width, cy = 0.5 * source.height;
  double x[3] = {cx, cx + 1.0, cx};
  double y[3] = {cy, cy, cy + 1.0};
  double z[3] = {0.0, 0.0, 0.0};
  int ok[3] = {0, 0, 0};
  GDALGenImgProjTransform(transformer, FALSE, 3, x, y, z, ok);
  if (!ok[0] || !ok[1] || !ok[2]) return 0.0;
  const double along_col = std::hypot(x[1] - x[0], y[1] - y[0]);
  const double along_row = std::hypot(x[2] - x[0], y[2] - y[0]);
  return std::sqrt(along_col * along_row);
}

// Wraps `values` (already sized to the grid) as band 1 of a MEM dataset, so GDAL warps straight
// into the caller's buffer without a copy.
template <typename T>
GDALDatasetUniquePtr WrapAsTarget(const Grid& grid, std::vector<T>& values) {
  constexpr GDALDataType kType = std::is_same_v<T, float> ? GDT_Float32 : GDT_Float64;
  GDALDatasetUniquePtr target = CreateMemDataset(grid, 0, kType, "cone_index");
  char pointer_text[64] = {};
  const int length = CPLPrintPointer(pointer_text, values.data(), sizeof(pointer_text) - 1);
  pointer_text[length] = '\0';
  char** band_options = CSLSetNameValue(nullptr, "DATAPOINTER", pointer_text);
  const CPLErr added = target->AddBand(kType, band_options);
  CSLDestroy(band_options);
  if (added != CE_None) throw std::runtime_error("cannot wrap the warp target buffer");
  target->GetRasterBand(1)->SetNoDataValue(std::numeric_limits<double>::quiet_NaN());
  return target;
}

// Resampling used by WarpInto.
enum class Method { kAverageOrBilinear, kBilinear, kNearest };

template <typename T>
std::vector<T> WarpInto(const OpenedRaster& source, const Grid& grid, Method method,
                        const std::string& field) {
  std::vector<T> values(static_cast<size_t>(grid.CellCount()), std::numeric_limits<T>::quiet_NaN());
  GDALDatasetUniquePtr target = WrapAsTarget(grid, values);
  GDALDatasetH source_h = GDALDataset::ToHandle(source.dataset.get());
  GDALDatasetH target_h = GDALDataset::ToHandle(target.get());

  WarpResources res;
  CPLErrorReset();
  res.transformer = GDALCreateGenImgProjTransformer2(source_h, target_h, nullptr);
  Require(res.transformer != nullptr, field,
          "cannot transform from its CRS to the cone-index CRS: " + GdalErrorScope::LastMessage());
  GDALResampleAlg resampling = GRA_NearestNeighbour;
  if (method == Method::kBilinear) {
    resampling = GRA_Bilinear;
  } else if (method == Method::kAverageOrBilinear) {
    resampling =
        SourceCellsInOutputCells(res.transformer, source) > 1.0 ? GRA_Bilinear : GRA_Average;
  }
  res.approx_transformer =
      GDALCreateApproxTransformer(GDALGenImgProjTransform, res.transformer, kApproxMaxErrorPixels);

  GDALWarpOptions* options = res.options = GDALCreateWarpOptions();
  options->hSrcDS = source_h;
  options->hDstDS = target_h;
  options->eResampleAlg = resampling;
  options->nBandCount = 1;
  options->panSrcBands = static_cast<int*>(CPLMalloc(sizeof(int)));
  options->panSrcBands[0] = 1;
  options->panDstBands = static_cast<int*>(CPLMalloc(sizeof(int)));
  options->panDstBands[0] = 1;
  // Source nodata: the band's own value if it has one. Otherwise GDAL applies the band's mask
  // (alpha or internal mask) by itself; with no mask either, NaN is declared as nodata so that NaN
  // cells of a float raster do not spread through averaging.
  int has_nodata = FALSE;
  const double source_nodata = source.band1->GetNoDataValue(&has_nodata);
  const bool mask_only = !has_nodata && (source.band1->GetMaskFlags() & GMF_ALL_VALID) == 0;
  if (!mask_only) {
    options->padfSrcNoDataReal = static_cast<double*>(CPLMalloc(sizeof(double)));
    options->padfSrcNoDataReal[0] =
        has_nodata ? source_nodata : std::numeric_limits<double>::quiet_NaN();
  }
  options->padfDstNoDataReal = static_cast<double*>(CPLMalloc(sizeof(double)));
  options->padfDstNoDataReal[0] = std::numeric_limits<double>::quiet_NaN();
  options->papszWarpOptions = CSLSetNameValue(options->papszWarpOptions, "INIT_DEST", "NO_DATA");
  if (method == Method::kBilinear) {
    // Plain 2 x 2 interpolation at each output cell centre. When shrinking, GDAL would otherwise
    // widen the kernel, and its discrete weights shift the sampled point by a fraction of a
    // source cell from one output cell to the next (about 2 % slope noise on a plane).
    options->papszWarpOptions = CSLSetNameValue(options->papszWarpOptions, "XSCALE", "1");
    options->papszWarpOptions = CSLSetNameValue(options->papszWarpOptions, "YSCALE", "1");
  }
  options->pfnTransformer = GDALApproxTransform;
  options->pTransformerArg = res.approx_transformer;

  GDALWarpOperation operation;
  CPLErrorReset();
  // GDAL is called before each message is built: argument evaluation order is unspecified.
  const CPLErr initialized = operation.Initialize(options);
  Require(initialized == CE_None, field,
          "cannot set up warping onto the cone-index grid: " + GdalErrorScope::LastMessage());
  const CPLErr warped = operation.ChunkAndWarpImage(0, 0, grid.width, grid.height);
  Require(warped == CE_None, field,
          "warping onto the cone-index grid failed: " + GdalErrorScope::LastMessage());
  target.reset();  // the MEM dataset never owned `values`
  return values;
}

}  // namespace

std::vector<float> WarpContinuous(const OpenedRaster& source, const Grid& grid,
                                  ContinuousMethod method, const std::string& field) {
  return WarpInto<float>(
      source, grid,
      method == ContinuousMethod::kBilinear ? Method::kBilinear : Method::kAverageOrBilinear,
      field);
}

std::vector<double> WarpCategorical(const OpenedRaster& source, const Grid& grid,
                                    const std::string& field) {
  return WarpInto<double>(source, grid, Method::kNearest, field);
}

}  // namespace gonogo::geo::internal
