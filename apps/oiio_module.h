#pragma once
// The image work that needs OpenImageIO — EXR and JPEG files, image formats other than PNG, and the
// frame plots' line and text drawing — lives in a module loaded on first use
// (libcuberille_oiio.so, beside the program). Debian's OpenImageIO links about 250 shared
// libraries (ffmpeg, OpenCV, GDAL, GStreamer...); linked into the program, the dynamic loader
// spent ~0.16 s of every run on them, more than a small render takes. A run that reads and
// writes only PNG (apps/png_file.h) never loads them: it pays at start-up only for what it uses.

#include <string>
#include <vector>

#include "apps/frame_plot.h"
#include "raster/resolve.h"

namespace cuberille::apps {

/// What the module provides. Errors come back as messages (empty: success), not exceptions,
/// so nothing but plain data crosses the module boundary's error path.
struct OiioModule {
    static constexpr int kInterfaceVersion = 2;
    int interfaceVersion = kInterfaceVersion;
    std::string (*writeExr)(const std::string& path, const raster::Image& image);
    std::string (*readImage)(const std::string& path, raster::Image& image);
    /// 8-bit RGB, sRGB-encoded, row-major; quality 1-100.
    std::string (*writeJpeg)(const std::string& path, int width, int height, const std::vector<uint8_t>& rgb, int quality);
    raster::Image (*drawFramePlot)(const std::vector<PlotPanel>& panels, const PlotLayout& layout, std::string* warning);
};

/// The module's entry point, looked up by name (extern "C": no mangling).
inline constexpr const char* kOiioModuleEntryPoint = "cuberilleOiioModule";
inline constexpr const char* kOiioModuleFileName = "libcuberille_oiio.so";

/// Loads the module on first use (thread-safe) and returns it. Throws std::runtime_error saying
/// where it looked when it cannot be loaded.
const OiioModule& oiioModule();

}  // namespace cuberille::apps
