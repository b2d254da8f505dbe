#pragma once
// A rendered image as a display shows it: sRGB-encoded 8- or 16-bit samples, straight colour
// beside alpha, and the depth view made legible. One encoding for every output, so the pixels
// the command line writes to a PNG and the array the Python module returns are the same bytes.

#include <cstdint>
#include <vector>

#include "raster/resolve.h"
#include "render/frame_settings.h"

namespace cuberille::render {

/// The depth view's greys in an 8-bit file: the nearest covered pixel this display value, the
/// farthest this one, evenly spaced between (a 1920x1080 view of a deep scene uses every code
/// between), uncovered pixels black. EXR keeps the distances themselves.
inline constexpr double kNearestGrey = 1.0, kFarthestGrey = 0.15;

/// The depth view's distances (raster::resolveViewDistance) as greys an 8-bit file can show.
raster::Image legibleDepth(const raster::Image& distances);

/// The image an 8- or 16-bit file shows for a view: the depth view's distances made legible
/// (`depthIsDistance`: a 3D scene's depth view; a 2D .tri scene's is the stored depth), any
/// other view as it is: `image` itself, not a copy (33 MB at 1920x1080), or the legible depth,
/// made in `legible`.
const raster::Image& displayImage(const raster::Image& image, View view, bool depthIsDistance, raster::Image& legible);

/// The image's pixels as 8- or 16-bit samples (16-bit ones as host-order pairs of bytes):
/// sRGB-encoded straight colour, then linear alpha when `alpha`; 3 or 4 samples a pixel.
std::vector<uint8_t> encodeDisplayPixels(const raster::Image& image, bool alpha, int bits);

/// Four 8-bit samples a pixel: encodeDisplayPixels' RGB with alpha 255 when `alpha` is false
/// (what a PNG without alpha shows), its RGBA when true.
std::vector<uint8_t> displayRgba8(const raster::Image& image, bool alpha);

}  // namespace cuberille::render
