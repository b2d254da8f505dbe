#pragma once
// plotFrames()'s drawing with OpenImageIO, inside the OpenImageIO module (apps/oiio_module.h).

#include "apps/frame_plot.h"

namespace cuberille::apps {

raster::Image drawFramePlot(const std::vector<PlotPanel>& panels, const PlotLayout& layout, std::string* warning);

}  // namespace cuberille::apps
