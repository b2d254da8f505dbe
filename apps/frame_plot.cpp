#include "apps/frame_plot.h"

#include "apps/oiio_module.h"

namespace cuberille::apps {

// Drawn in the OpenImageIO module (apps/frame_plot_drawing.cpp), loaded only by runs that plot.
raster::Image plotFrames(const std::vector<PlotPanel>& panels, const PlotLayout& layout, std::string* warning) {
    return oiioModule().drawFramePlot(panels, layout, warning);
}

}  // namespace cuberille::apps
