#!/usr/bin/python3
"""Writes a deterministic synthetic terrain for trying gonogo end to end.

Run with Debian's interpreter, which has GDAL's Python bindings and numpy:

    /usr/bin/python3 clients/sample-data/make_sample_terrain.py --out /tmp/terrain
    /usr/bin/python3 clients/sample-data/make_sample_terrain.py --out /tmp/big --size 1000

Files written to --out (all on one grid of --size x --size cells of --cell-m metres, in
WGS 84 / UTM zone 17N, EPSG:32617, centred on 36.1 N 81.0 W in the Blue Ridge of North Carolina;
zone 17's central meridian runs through the centre, so grid and ground distances agree to 0.04 %):

    elevation.tif   Float32, metres: smooth hills; Horn slopes span 0 to 80 %
    slope.tif       Float32, percent (100 * tan angle): Horn (1981) slope of elevation.tif, computed
                    the way the server does (one-sided differences at the edges)
    cone_index.tif  Float32, kPa: soft wet ground (100-300 kPa) in hollows, firm ground
                    (1000-3000 kPa) on the dry ground, a log-linear transition between them;
                    a few cells are nodata (-9999)
    soil_class.tif  Byte: 1 sand, 2 silt loam, 3 clay (0 = nodata)
    soil_table.json the soil classes with the remolding index the service applies:
                    rating cone index RCI = CI * remolding_index

The same arguments always give byte-identical rasters (fixed seed, no randomness from the clock).
GeoTIFFs are tiled and DEFLATE-compressed; --size 1000 writes about 3.5 MB.
"""

import argparse
import json
import os
import sys

import numpy as np
from osgeo import gdal, osr

SEED = 20240611
EPSG = 32617
CENTRE_EASTING_M = 500000.0  # zone 17N central meridian, 81 W
CENTRE_NORTHING_M = 3996000.0  # about 36.1 N
BASE_ELEVATION_M = 900.0
MAX_SLOPE_PERCENT = 80.0
CONE_NODATA = -9999.0
SOIL_NODATA = 0

SOIL_CLASSES = [
    # Remolding index: share of cone index left after traffic remoulds the soil (WES practice).
    # Clean sand loses little; wet clays lose most.
    # bekker_soil: the Bekker-Janosi parameter set the bekker tier uses (Wong, Theory of Ground
    # Vehicles, Table 2.3, via solvers/terramech/data/bekker_soils.csv); the library has no silt
    # loam, so the sandy loam stands in for it.
    {"code": 1, "name": "sand", "uscs": "SP", "remolding_index": 0.90,
     "bekker_soil": "lll_dry_sand"},
    {"code": 2, "name": "silt loam", "uscs": "ML", "remolding_index": 0.75,
     "bekker_soil": "lll_sandy_loam_15pct"},
    {"code": 3, "name": "clay", "uscs": "CH", "remolding_index": 0.55,
     "bekker_soil": "wes_lean_clay_32pct"},
]


def parse_args(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", required=True, help="output directory (created if missing)")
    parser.add_argument("--size", type=int, default=200, help="cells per side (default 200)")
    parser.add_argument("--cell-m", type=float, default=10.0,
                        help="cell size in metres (default 10)")
    args = parser.parse_args(argv)
    if args.size < 3:
        parser.error("--size must be at least 3")
    if not args.cell_m > 0:
        parser.error("--cell-m must be positive")
    return args


def blobs(rng, u, v, count, sigma_range, signed):
    """Sum of `count` random Gaussian bumps on the unit square, scaled to [0, 1]."""
    field = np.zeros_like(u)
    for _ in range(count):
        cu, cv = rng.uniform(0.05, 0.95, size=2)
        sigma = rng.uniform(*sigma_range)
        amplitude = rng.uniform(-1.0, 1.0) if signed else rng.uniform(0.3, 1.0)
        field += amplitude * np.exp(-((u - cu) ** 2 + (v - cv) ** 2) / (2.0 * sigma**2))
    lo, hi = field.min(), field.max()
    return (field - lo) / (hi - lo) if hi > lo else np.zeros_like(field)


def weighted_difference(z, axis):
    """Change of z per cell along `axis` (1 = columns/x, 0 = rows/y) by Horn's 1-2-1 weighted
    central differences; at edges a line missing one end uses its one-sided difference, a line
    missing more is dropped. Mirrors server/geo/slope.cc."""
    zp = np.pad(z.astype(np.float64), 1, constant_values=np.nan)
    h, w = z.shape
    total = np.zeros((h, w))
    weights = np.zeros((h, w))
    for line, weight in ((-1, 1.0), (0, 2.0), (1, 1.0)):
        def at(step):
            if axis == 1:
                return zp[1 + line:1 + line + h, 1 + step:1 + step + w]
            return zp[1 + step:1 + step + h, 1 + line:1 + line + w]

        before, middle, after = at(-1), at(0), at(1)
        ok_b, ok_m, ok_a = ~np.isnan(before), ~np.isnan(middle), ~np.isnan(after)
        per_cell = np.where(
            ok_b & ok_a, 0.5 * (after - before),
            np.where(ok_a & ok_m, after - middle, np.where(ok_b & ok_m, middle - before, np.nan)))
        usable = ~np.isnan(per_cell)
        total += np.where(usable, weight * per_cell, 0.0)
        weights += np.where(usable, weight, 0.0)
    return np.divide(total, weights, out=np.zeros_like(total), where=weights > 0)


def horn_slope_percent(z, cell_m):
    """Slope in percent, Horn (1981), Proc. IEEE 69(1): 14-47."""
    dz_dx = weighted_difference(z, axis=1) / cell_m
    dz_dy = weighted_difference(z, axis=0) / cell_m
    return 100.0 * np.hypot(dz_dx, dz_dy)


def make_fields(size, cell_m):
    rng = np.random.default_rng(SEED)
    centres = (np.arange(size) + 0.5) / size
    u, v = np.meshgrid(centres, centres)  # u east, v south (row order)

    # Elevation: hills and hollows plus a regional tilt, scaled so the steepest Horn slope is
    # MAX_SLOPE_PERCENT (slope is linear in relief), rounded to centimetres for compression.
    shape = blobs(rng, u, v, 24, (0.08, 0.20), signed=True) + 0.15 * u
    unit_slope = horn_slope_percent(shape, cell_m).max()
    elevation = BASE_ELEVATION_M + shape * (MAX_SLOPE_PERCENT / unit_slope)
    elevation = np.round(elevation, 2)
    slope = np.round(horn_slope_percent(elevation, cell_m), 3)

    # Wetness: high in hollows, plus smooth patches. The wettest ground is soft, the driest firm, and
    # the cone index falls log-linearly between them across a transition band (the 55-85 %
    # wetness quantiles), so that intermediate ground (300-1000 kPa) exists as in the field.
    low = 1.0 - (elevation - elevation.min()) / max(np.ptp(elevation), 1e-9)
    wet = 0.65 * low + 0.35 * blobs(rng, u, v, 20, (0.03, 0.10), signed=False)
    lo_q, hi_q = np.quantile(wet, 0.55), np.quantile(wet, 0.85)
    t = np.clip((wet - lo_q) / (hi_q - lo_q), 0.0, 1.0)
    t = t * t * (3.0 - 2.0 * t)  # smoothstep
    soft_kpa = 100.0 + 200.0 * blobs(rng, u, v, 10, (0.04, 0.12), signed=True)
    firm_kpa = 1000.0 + 2000.0 * blobs(rng, u, v, 10, (0.05, 0.15), signed=True)
    cone = np.round(np.exp((1.0 - t) * np.log(firm_kpa) + t * np.log(soft_kpa)))
    cone = cone.astype(np.float32)

    # A few nodata cells: two 3 x 3 gaps and scattered single cells.
    for _ in range(2):
        r, c = rng.integers(0, size - 3, size=2)
        cone[r:r + 3, c:c + 3] = CONE_NODATA
    singles = max(5, size * size // 2000)
    cone[rng.integers(0, size, singles), rng.integers(0, size, singles)] = CONE_NODATA

    # Soil: clay where wettest, sand on the driest ground, silt loam between.
    score = wet + 0.25 * (blobs(rng, u, v, 12, (0.05, 0.15), signed=True) - 0.5)
    soil = np.full((size, size), 2, dtype=np.uint8)
    soil[score > np.quantile(score, 0.70)] = 3
    soil[score < np.quantile(score, 0.30)] = 1
    return elevation.astype(np.float32), slope.astype(np.float32), cone, soil


def write_geotiff(path, array, cell_m, gdal_type, nodata, description, units):
    size = array.shape[0]
    predictor = "3" if gdal_type == gdal.GDT_Float32 else "2"
    driver = gdal.GetDriverByName("GTiff")
    ds = driver.Create(path, size, size, 1, gdal_type,
                       options=["TILED=YES", "COMPRESS=DEFLATE", "PREDICTOR=" + predictor])
    half_m = 0.5 * size * cell_m
    ds.SetGeoTransform([CENTRE_EASTING_M - half_m, cell_m, 0.0,
                        CENTRE_NORTHING_M + half_m, 0.0, -cell_m])
    srs = osr.SpatialReference()
    srs.ImportFromEPSG(EPSG)
    ds.SetProjection(srs.ExportToWkt())
    ds.SetMetadataItem("SOURCE", "gonogo make_sample_terrain.py seed=%d" % SEED)
    band = ds.GetRasterBand(1)
    if nodata is not None:
        band.SetNoDataValue(nodata)
    band.SetDescription(description)
    band.SetUnitType(units)
    band.WriteArray(array)
    ds = None


def main(argv):
    args = parse_args(argv)
    gdal.UseExceptions()
    os.makedirs(args.out, exist_ok=True)
    elevation, slope, cone, soil = make_fields(args.size, args.cell_m)

    def out(name):
        return os.path.join(args.out, name)

    write_geotiff(out("elevation.tif"), elevation, args.cell_m, gdal.GDT_Float32, None,
                  "elevation", "m")
    write_geotiff(out("slope.tif"), slope, args.cell_m, gdal.GDT_Float32, None, "slope", "%")
    write_geotiff(out("cone_index.tif"), cone, args.cell_m, gdal.GDT_Float32, CONE_NODATA,
                  "cone_index", "kPa")
    write_geotiff(out("soil_class.tif"), soil, args.cell_m, gdal.GDT_Byte, SOIL_NODATA,
                  "soil_class", "")
    table = {
        "description":
            "Soil classes of soil_class.tif (nodata %d); rating cone index RCI = CI * "
            "remolding_index" % SOIL_NODATA,
        "classes": SOIL_CLASSES,
    }
    with open(out("soil_table.json"), "w") as f:
        json.dump(table, f, indent=2)
        f.write("\n")

    valid = cone != CONE_NODATA
    total_bytes = sum(os.path.getsize(out(n)) for n in os.listdir(args.out)
                      if n.endswith((".tif", ".json")))
    print("wrote %s: %d x %d cells of %g m, EPSG:%d, %.2f MB" %
          (args.out, args.size, args.size, args.cell_m, EPSG, total_bytes / 1e6))
    print("  slope %.1f to %.1f %%; cone index %d-%d kPa (%.0f %% below 300, %.0f %% above 1000), "
          "%d nodata cells" %
          (slope.min(), slope.max(), cone[valid].min(), cone[valid].max(),
           100.0 * np.mean(cone[valid] < 300), 100.0 * np.mean(cone[valid] > 1000),
           np.count_nonzero(~valid)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
