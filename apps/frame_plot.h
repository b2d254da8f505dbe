#pragma once
// Per-frame measurements drawn as a PNG a person reads at a glance (the plots of Chajdas 2015,
// figures 34-39): panels stacked over a shared frame axis, each with its series as lines, a
// legend, its largest value on the y axis, and the frames after the path (settling) shaded.
// Drawn with OpenImageIO's line and text rendering; the labels need a FreeType font (DejaVu Sans,
// installed by the set-up script) and are left out with a warning when none is found.

#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "raster/resolve.h"

namespace cuberille::apps {

struct PlotSeries {
    std::string name;
    glm::vec3 color;
    std::vector<double> values;  // one per frame
};

struct PlotPanel {
    std::string title;  // with the unit, e.g. "frame time (ms)"
    std::vector<PlotSeries> series;
    std::vector<int> markers;  // frames marked with a vertical tick (events such as defragmentation)
    std::string markerName;
};

struct PlotLayout {
    std::string title;
    int widthPixels = 1400, panelHeightPixels = 240;
    int firstSettlingFrame = -1;  // frames from here on are shaded; -1: none
};

/// The plot as an image (linear RGB; write it with writeImageAtomically). `warning` receives a
/// line when the labels could not be drawn.
raster::Image plotFrames(const std::vector<PlotPanel>& panels, const PlotLayout& layout, std::string* warning);

}  // namespace cuberille::apps
