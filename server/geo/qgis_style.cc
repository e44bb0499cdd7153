#include "server/geo/qgis_style.h"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "server/geo/products.h"
#include "server/geo/quicklook.h"

namespace gonogo::geo::internal {
namespace {

std::string Hex(Rgba c) {
  char text[8];
  std::snprintf(text, sizeof text, "#%02x%02x%02x", c.r, c.g, c.b);
  return text;
}

std::string Number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", v);
  return text;
}

// Everything of a .qml before and after the <rasterrenderer> element.
constexpr char kQmlHead[] = R"(<!DOCTYPE qgis PUBLIC 'http://mrcc.com/qgis.dtd' 'SYSTEM'>
<qgis version="3.22.16-Białowieża" styleCategories="AllStyleCategories" hasScaleBasedVisibilityFlag="0" minScale="1e+08" maxScale="0">
  <pipe>
    <provider>
      <resampling enabled="false" zoomedInResamplingMethod="nearestNeighbour" zoomedOutResamplingMethod="nearestNeighbour" maxOversampling="2"/>
    </provider>
)";
constexpr char kQmlTail[] = R"(    <brightnesscontrast brightness="0" contrast="0" gamma="1"/>
    <huesaturation saturation="0" grayscaleMode="0" invertColors="0" colorizeOn="0" colorizeRed="255" colorizeGreen="128" colorizeBlue="128" colorizeStrength="100"/>
    <rasterresampler maxOversampling="2"/>
    <resamplingStage>resamplingFilter</resamplingStage>
  </pipe>
  <blendMode>0</blendMode>
</qgis>
)";
constexpr char kMinMaxOrigin[] = R"(      <minMaxOrigin>
        <limits>None</limits>
        <extent>WholeRaster</extent>
        <statAccuracy>Estimated</statAccuracy>
        <cumulativeCutLower>0.02</cumulativeCutLower>
        <cumulativeCutUpper>0.98</cumulativeCutUpper>
        <stdDevFactor>2</stdDevFactor>
      </minMaxOrigin>
)";

// ColorBrewer RdYlGn, 5 classes: slow red, fast green, like the class map.
constexpr Rgba kSpeedRamp[] = {{215, 25, 28, 255},
                               {253, 174, 97, 255},
                               {255, 255, 191, 255},
                               {166, 217, 106, 255},
                               {26, 150, 65, 255}};

}  // namespace

std::string ClassStyleQml() {
  struct Entry {
    uint8_t value;
    const char* label;
  };
  // Legend order GO, SLOW-GO, NO-GO, as on the quicklook.
  const Entry entries[] = {{kClassGo, "GO"}, {kClassSlowGo, "SLOW-GO"}, {kClassNoGo, "NO-GO"}};
  std::ostringstream qml;
  qml << kQmlHead
      << R"(    <rasterrenderer type="paletted" band="1" opacity="1" alphaBand="-1" nodataColor="">
      <rasterTransparency/>
)" << kMinMaxOrigin
      << "      <colorPalette>\n";
  for (const Entry& e : entries) {
    qml << "        <paletteEntry value=\"" << int{e.value} << "\" color=\""
        << Hex(ClassColour(e.value)) << "\" alpha=\"255\" label=\"" << e.label << "\"/>\n";
  }
  qml << "      </colorPalette>\n    </rasterrenderer>\n" << kQmlTail;
  return qml.str();
}

std::string SpeedStyleQml(double max_kmh) {
  const std::string max = Number(max_kmh);
  std::ostringstream qml;
  qml << kQmlHead
      << R"(    <rasterrenderer type="singlebandpseudocolor" band="1" opacity="1" alphaBand="-1" nodataColor="" classificationMin="0" classificationMax=")"
      << max << R"(">
      <rasterTransparency/>
)" << kMinMaxOrigin
      << R"(      <rastershader>
        <colorrampshader colorRampType="INTERPOLATED" classificationMode="1" clip="0" minimumValue="0" maximumValue=")"
      << max << R"(" labelPrecision="0">
)";
  constexpr int kStops = sizeof(kSpeedRamp) / sizeof(kSpeedRamp[0]);
  for (int i = 0; i < kStops; ++i) {
    const double kmh = max_kmh * i / (kStops - 1);
    qml << "          <item value=\"" << Number(kmh) << "\" color=\"" << Hex(kSpeedRamp[i])
        << "\" alpha=\"255\" label=\"" << Number(kmh) << " km/h\"/>\n";
  }
  // A continuous bar in the layer legend, its ends labelled in km/h.
  qml << R"(          <rampLegendSettings minimumLabel="" maximumLabel="" prefix="" suffix=" km/h" direction="0" useContinuousLegend="1" orientation="2">
            <numericFormat id="basic"/>
          </rampLegendSettings>
        </colorrampshader>
      </rastershader>
    </rasterrenderer>
)" << kQmlTail;
  return qml.str();
}

double SpeedRampMaxKmh(double highest_kmh) {
  constexpr double kStepKmh = 5.0;
  if (!(highest_kmh > kStepKmh)) return kStepKmh;
  return std::ceil(highest_kmh / kStepKmh) * kStepKmh;
}

}  // namespace gonogo::geo::internal
