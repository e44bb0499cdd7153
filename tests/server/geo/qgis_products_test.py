#!/usr/bin/python3
"""The map products opened in real GIS software, as a user would open them.

QGIS (Debian python3-qgis, rendered offscreen) loads gonogo.tif and speed.tif from their folder and
applies gonogo.qml and speed.qml on its own; the test checks the legend QGIS builds (labels and
colours), renders each layer at one pixel per cell and compares every pixel with the class or the
speed ramp, and checks that without the styles the class names still come from the
gonogo.tif.aux.xml sidecar. The STAC item.json validates against the STAC 1.0.0 item schema and the
projection extension schema (tests/data/stac, python3-jsonschema), and an item with a defect does
not. It also exports a QGIS print layout of both layers with their legends (qgis_products.png, the
picture in README.md).

    qgis_products_test.py --writer build/tests/server/geo/geo_write_sample_products \\
        --out DIR --stac-schemas tests/data/stac
    qgis_products_test.py --products out/sample --out DIR --stac-schemas tests/data/stac

With --writer the products are written by it (the synthetic map of write_sample_products.cc) and
every rendered pixel is checked; with --products an existing folder (e.g. a downloaded job) gets
the same checks except the pixel comparisons, which need to know the map.
"""
import argparse
import copy
import glob
import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

ARGS = None
PRODUCTS = None  # folder of the products under test

CLASS_COLOURS = {0: (215, 25, 28), 1: (255, 176, 0), 2: (26, 150, 65)}
CLASS_LEGEND = [("GO", (26, 150, 65)), ("SLOW-GO", (255, 176, 0)), ("NO-GO", (215, 25, 28))]
# The print layout: two square maps side by side, each with its legend to its right.
PAGE_MM = (350, 124)
MAP_X_MM = (6, 180)
MAP_Y_MM = 18
MAP_MM = 100
SPEED_RAMP = [(215, 25, 28), (253, 174, 97), (255, 255, 191), (166, 217, 106), (26, 150, 65)]


def setUpModule():
    global QGS_APP, QT_FOLDER
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    # Qt's runtime directory and its temporary files (qt_temp-*) in one folder, removed at the end.
    QT_FOLDER = tempfile.mkdtemp(prefix="qgis_runtime_")
    os.chmod(QT_FOLDER, 0o700)
    os.environ["XDG_RUNTIME_DIR"] = QT_FOLDER
    os.environ["TMPDIR"] = QT_FOLDER
    from qgis.core import QgsApplication
    QGS_APP = QgsApplication([], False)
    QGS_APP.initQgis()


def tearDownModule():
    QGS_APP.exitQgis()
    shutil.rmtree(QT_FOLDER, ignore_errors=True)


def rgb(colour):
    return (colour.red(), colour.green(), colour.blue())


def load(path, name):
    from qgis.core import QgsRasterLayer
    layer = QgsRasterLayer(path, name)  # loads NAME.qml beside the file, as QGIS's browser does
    assert layer.isValid(), path + " does not open in QGIS"
    return layer


def legend_labels(layer):
    """The labels QGIS's Layers panel shows under the layer."""
    from qgis.core import QgsLayerTreeLayer
    from qgis.PyQt.QtCore import Qt
    nodes = layer.legend().createLayerTreeModelLegendNodes(QgsLayerTreeLayer(layer))
    return [node.data(Qt.DisplayRole) for node in nodes]


def render(layer, width, height):
    """The layer drawn over its extent at width x height pixels on a transparent background."""
    from qgis.core import QgsMapRendererSequentialJob, QgsMapSettings
    from qgis.PyQt.QtCore import QSize
    from qgis.PyQt.QtGui import QColor
    settings = QgsMapSettings()
    settings.setLayers([layer])
    settings.setDestinationCrs(layer.crs())
    settings.setExtent(layer.extent())
    settings.setOutputSize(QSize(width, height))
    settings.setBackgroundColor(QColor(0, 0, 0, 0))
    job = QgsMapRendererSequentialJob(settings)
    job.start()
    job.waitForFinished()
    return job.renderedImage()


def read_band(path):
    from osgeo import gdal
    gdal.UseExceptions()
    ds = gdal.Open(path)
    return ds.GetRasterBand(1).ReadAsArray()


class ClassLayer(unittest.TestCase):
    def test_qgis_shows_three_labelled_classes_in_their_colours(self):
        layer = load(os.path.join(PRODUCTS, "gonogo.tif"), "gonogo")
        renderer = layer.renderer()
        self.assertEqual(renderer.type(), "paletted")
        classes = [(c.value, c.label, rgb(c.color)) for c in renderer.classes()]
        self.assertEqual(classes, [(2, "GO", CLASS_COLOURS[2]), (1, "SLOW-GO", CLASS_COLOURS[1]),
                                   (0, "NO-GO", CLASS_COLOURS[0])])
        # Under the band's name, as QGIS titles a paletted band.
        self.assertEqual(legend_labels(layer),
                         ["Band 1: go_class (Palette)", "GO", "SLOW-GO", "NO-GO"])
        symbology = [(label, rgb(colour)) for label, colour in renderer.legendSymbologyItems()]
        self.assertEqual(symbology, CLASS_LEGEND)
        self.assertEqual(layer.dataProvider().sourceNoDataValue(1), 255)

    def test_rendered_map_has_the_class_colour_in_every_cell(self):
        layer = load(os.path.join(PRODUCTS, "gonogo.tif"), "gonogo")
        classes = read_band(os.path.join(PRODUCTS, "gonogo.tif"))
        height, width = classes.shape
        image = render(layer, width, height)
        image.save(os.path.join(ARGS.out, "qgis_gonogo.png"))
        if ARGS.writer is None:
            return
        wrong = 0
        counts = {0: 0, 1: 0, 2: 0, 255: 0}
        for row in range(height):
            for col in range(width):
                value = int(classes[row, col])
                counts[value] += 1
                pixel = image.pixelColor(col, row)
                if value == 255:
                    wrong += pixel.alpha() != 0
                else:
                    wrong += pixel.alpha() != 255 or rgb(pixel) != CLASS_COLOURS[value]
        self.assertTrue(all(n > 500 for n in counts.values()), counts)  # every class is drawn
        self.assertEqual(wrong, 0, "%d of %d pixels differ from their class" % (wrong,
                                                                              width * height))

    def test_without_the_style_the_class_names_come_from_the_sidecar(self):
        folder = tempfile.mkdtemp(prefix="gonogo_nostyle_")
        try:
            shutil.copy(os.path.join(PRODUCTS, "gonogo.tif"), folder)
            bare = load(os.path.join(folder, "gonogo.tif"), "bare")
            self.assertEqual(legend_labels(bare)[1:4], ["0", "1", "2"])
            shutil.copy(os.path.join(PRODUCTS, "gonogo.tif.aux.xml"), folder)
            named = load(os.path.join(folder, "gonogo.tif"), "named")
            self.assertEqual(named.renderer().type(), "paletted")
            self.assertEqual(legend_labels(named)[1:4], ["NO-GO", "SLOW-GO", "GO"])
        finally:
            shutil.rmtree(folder)


class SpeedLayer(unittest.TestCase):
    def ramp_colour(self, kmh, max_kmh):
        """The colour QGIS's interpolated ramp gives `kmh` (linear between the five stops)."""
        position = min(max(kmh / max_kmh, 0.0), 1.0) * (len(SPEED_RAMP) - 1)
        lower = min(int(position), len(SPEED_RAMP) - 2)
        t = position - lower
        return tuple(a + t * (b - a) for a, b in zip(SPEED_RAMP[lower], SPEED_RAMP[lower + 1]))

    def test_qgis_shows_a_ramp_labelled_in_kmh(self):
        layer = load(os.path.join(PRODUCTS, "speed.tif"), "speed")
        renderer = layer.renderer()
        self.assertEqual(renderer.type(), "singlebandpseudocolor")
        shader = renderer.shader().rasterShaderFunction()
        items = shader.colorRampItemList()
        self.assertEqual(len(items), 5)
        self.assertEqual(items[0].value, 0.0)
        self.assertEqual(items[0].label, "0 km/h")
        self.assertTrue(all(item.label.endswith(" km/h") for item in items))
        self.assertEqual([rgb(item.color) for item in items], SPEED_RAMP)
        self.assertEqual(shader.legendSettings().suffix(), " km/h")
        if ARGS.writer is not None:
            # The fastest cell is 40 km/h: the ramp ends there.
            self.assertEqual([item.label for item in items],
                             ["0 km/h", "10 km/h", "20 km/h", "30 km/h", "40 km/h"])

    def test_rendered_speeds_follow_the_ramp_and_nodata_is_clear(self):
        import math
        layer = load(os.path.join(PRODUCTS, "speed.tif"), "speed")
        speeds = read_band(os.path.join(PRODUCTS, "speed.tif"))
        height, width = speeds.shape
        image = render(layer, width, height)
        image.save(os.path.join(ARGS.out, "qgis_speed.png"))
        if ARGS.writer is None:
            return
        max_kmh = layer.renderer().classificationMax()
        worst = 0.0
        nodata_wrong = 0
        for row in range(height):
            for col in range(width):
                kmh = float(speeds[row, col])
                pixel = image.pixelColor(col, row)
                if math.isnan(kmh):
                    nodata_wrong += pixel.alpha() != 0
                    continue
                expected = self.ramp_colour(kmh, max_kmh)
                worst = max(worst, max(abs(a - b) for a, b in zip(rgb(pixel), expected)))
        self.assertEqual(nodata_wrong, 0)
        # QGIS rounds the interpolated colour to whole levels.
        self.assertLessEqual(worst, 2.0)


class PrintLayout(unittest.TestCase):
    def test_layout_with_both_layers_and_their_legends_exports(self):
        from qgis.core import (QgsLayoutExporter, QgsLayoutItemLabel, QgsLayoutItemLegend,
                               QgsLayoutItemMap, QgsLayoutPoint, QgsLayoutSize, QgsPrintLayout,
                               QgsProject, QgsUnitTypes)
        from qgis.PyQt.QtGui import QFont, QImage
        project = QgsProject.instance()
        project.clear()
        classes = load(os.path.join(PRODUCTS, "gonogo.tif"), "Go / no-go class")
        speed = load(os.path.join(PRODUCTS, "speed.tif"), "Speed")
        project.addMapLayers([classes, speed])
        layout = QgsPrintLayout(project)
        layout.initializeDefaults()
        page = layout.pageCollection().page(0)
        page.setPageSize(QgsLayoutSize(PAGE_MM[0], PAGE_MM[1], QgsUnitTypes.LayoutMillimeters))
        title = QgsLayoutItemLabel(layout)
        from qgis.core import Qgis
        title.setText("gonogo.tif and speed.tif opened in QGIS %s with their styles"
                      % Qgis.QGIS_VERSION.split("-")[0])
        title.setFont(QFont("DejaVu Sans", 14))
        title.attemptMove(QgsLayoutPoint(6, 4, QgsUnitTypes.LayoutMillimeters))
        title.attemptResize(QgsLayoutSize(280, 10, QgsUnitTypes.LayoutMillimeters))
        layout.addLayoutItem(title)
        for index, layer in enumerate([classes, speed]):
            x_mm = MAP_X_MM[index]
            item = QgsLayoutItemMap(layout)
            item.setKeepLayerSet(True)  # draw this layer only, not the project's
            item.setLayers([layer])
            item.setCrs(layer.crs())
            item.setFrameEnabled(True)
            item.attemptMove(QgsLayoutPoint(x_mm, MAP_Y_MM, QgsUnitTypes.LayoutMillimeters))
            item.attemptResize(QgsLayoutSize(MAP_MM, MAP_MM, QgsUnitTypes.LayoutMillimeters))
            item.setExtent(layer.extent())
            layout.addLayoutItem(item)
            legend = QgsLayoutItemLegend(layout)
            legend.setLinkedMap(item)
            legend.setAutoUpdateModel(False)
            legend.model().rootGroup().clear()
            legend.model().rootGroup().addLayer(layer)
            legend.setTitle("")
            legend.attemptMove(QgsLayoutPoint(x_mm + MAP_MM + 2, MAP_Y_MM,
                                              QgsUnitTypes.LayoutMillimeters))
            layout.addLayoutItem(legend)
        path = os.path.join(ARGS.out, "qgis_products.png")
        settings = QgsLayoutExporter.ImageExportSettings()
        settings.dpi = 96
        result = QgsLayoutExporter(layout).exportToImage(path, settings)
        self.assertEqual(result, QgsLayoutExporter.Success)
        image = QImage(path)
        px_per_mm = 96 / 25.4
        self.assertLessEqual(abs(image.width() - PAGE_MM[0] * px_per_mm), 1)

        def colours_in_map(index):
            """How often each colour occurs inside map `index`'s frame (every 2nd pixel)."""
            counts = {}
            x0 = int((MAP_X_MM[index] + 1) * px_per_mm)
            y0 = int((MAP_Y_MM + 1) * px_per_mm)
            size = int((MAP_MM - 2) * px_per_mm)
            for y in range(y0, y0 + size, 2):
                for x in range(x0, x0 + size, 2):
                    colour = rgb(image.pixelColor(x, y))
                    counts[colour] = counts.get(colour, 0) + 1
            return counts

        # The class map is drawn: each class covers a good part of its frame (legend swatches,
        # outside the frame, do not count).
        class_counts = colours_in_map(0)
        for name, colour in CLASS_LEGEND:
            self.assertGreater(class_counts.get(colour, 0), 500, name)
        # The speed map is drawn: many ramp colours, the 0 km/h red among them.
        speed_counts = colours_in_map(1)
        self.assertGreater(len(speed_counts), 20)
        self.assertGreater(speed_counts.get(SPEED_RAMP[0], 0), 500)
        project.clear()


class StacItem(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        import jsonschema
        cls.jsonschema = jsonschema
        store = {}
        for path in glob.glob(os.path.join(ARGS.stac_schemas, "*.json")):
            with open(path) as f:
                schema = json.load(f)
            store[schema["$id"].rstrip("#")] = schema
        cls.item_schema = store[
            "https://schemas.stacspec.org/v1.0.0/item-spec/json-schema/item.json"]
        cls.proj_schema = store["https://stac-extensions.github.io/projection/v1.1.0/schema.json"]
        cls.store = store
        with open(os.path.join(PRODUCTS, "item.json")) as f:
            cls.item = json.load(f)

    def errors(self, schema, item):
        resolver = self.jsonschema.RefResolver(schema["$id"], schema, store=self.store)
        validator = self.jsonschema.Draft7Validator(
            schema, resolver=resolver, format_checker=self.jsonschema.FormatChecker())
        return [e.message for e in validator.iter_errors(item)]

    def test_item_validates_against_the_stac_item_and_projection_schemas(self):
        self.assertEqual(self.errors(self.item_schema, self.item), [])
        self.assertIn("https://stac-extensions.github.io/projection/v1.1.0/schema.json",
                      self.item["stac_extensions"])
        self.assertEqual(self.errors(self.proj_schema, self.item), [])

    def test_the_schemas_reject_a_defective_item(self):
        no_bbox = copy.deepcopy(self.item)
        del no_bbox["bbox"]
        self.assertNotEqual(self.errors(self.item_schema, no_bbox), [])
        open_ring = copy.deepcopy(self.item)
        open_ring["geometry"]["coordinates"][0] = open_ring["geometry"]["coordinates"][0][:3]
        self.assertNotEqual(self.errors(self.item_schema, open_ring), [])
        bad_shape = copy.deepcopy(self.item)
        bad_shape["properties"]["proj:shape"] = [10]
        self.assertNotEqual(self.errors(self.proj_schema, bad_shape), [])

    def test_every_asset_is_a_file_beside_the_item_and_bbox_is_in_degrees(self):
        for name, asset in self.item["assets"].items():
            self.assertTrue(os.path.isfile(os.path.join(PRODUCTS, asset["href"])), name)
            self.assertTrue(asset["roles"], name)
        west, south, east, north = self.item["bbox"]
        self.assertTrue(-180 <= west < east <= 180 and -90 <= south < north <= 90,
                        self.item["bbox"])
        from osgeo import gdal, osr
        ds = gdal.Open(os.path.join(PRODUCTS, "gonogo.tif"))
        gt = ds.GetGeoTransform()
        native = osr.SpatialReference(wkt=ds.GetProjection())
        wgs84 = osr.SpatialReference()
        wgs84.ImportFromEPSG(4326)
        for srs in (native, wgs84):
            srs.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
        to_wgs84 = osr.CoordinateTransformation(native, wgs84)
        for col, row in ((0, 0), (ds.RasterXSize, 0), (0, ds.RasterYSize),
                         (ds.RasterXSize, ds.RasterYSize)):
            lon, lat, _ = to_wgs84.TransformPoint(gt[0] + col * gt[1], gt[3] + row * gt[5])
            inside = west - 1e-9 <= lon <= east + 1e-9 and south - 1e-9 <= lat <= north + 1e-9
            self.assertTrue(inside,
                            (lon, lat, self.item["bbox"]))


def main():
    global ARGS, PRODUCTS
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--writer", help="geo_write_sample_products, run into OUT/products")
    source.add_argument("--products", help="an existing products folder")
    parser.add_argument("--out", required=True, help="folder for the rendered PNGs")
    parser.add_argument("--stac-schemas", required=True, help="tests/data/stac")
    ARGS, rest = parser.parse_known_args()
    os.makedirs(ARGS.out, exist_ok=True)
    if ARGS.writer is not None:
        PRODUCTS = os.path.join(ARGS.out, "products")
        shutil.rmtree(PRODUCTS, ignore_errors=True)
        subprocess.run([ARGS.writer, PRODUCTS], check=True, stdout=subprocess.DEVNULL)
    else:
        PRODUCTS = ARGS.products
    result = unittest.main(argv=[sys.argv[0], "-v"] + rest, exit=False).result
    print("%d passed, %d failed" % (result.testsRun - len(result.failures) - len(result.errors),
                                     len(result.failures) + len(result.errors)))
    sys.exit(0 if result.wasSuccessful() else 1)


if __name__ == "__main__":
    main()
