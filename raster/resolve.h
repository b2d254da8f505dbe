#pragma once
// Resolve: from per-sample storage to one linear RGBA value per pixel (box filter), plus the
// teaching views that read the same framebuffer: depth, overdraw and coarse block classes.
//
// The box average sums a pixel's samples in double (exact for any samples of comparable
// magnitude) and divides by the sample count, a power of two: the one rounding is the final
// conversion to float. So k of N samples at value v resolve to float(k·v/N) (DESIGN.md, .tri).

#include <vector>

#include "raster/framebuffer.h"
#include "raster/uninitialized_allocator.h"

namespace cuberille::raster {

/// Linear RGBA float image, row-major, top row first.
struct Image {
    int width = 0, height = 0;
    // A resize leaves new values unwritten: the resolve writes every one, on its threads, so a
    // fresh process takes the image's page faults there and not in a zero-fill on one thread
    // first (33 MB at 1080p).
    UninitializedVector<float> rgba;

    float* pixel(int x, int y) { return rgba.data() + (size_t(y) * width + x) * 4; }
    const float* pixel(int x, int y) const { return rgba.data() + (size_t(y) * width + x) * 4; }
};

/// A depth-only target resolves to its clear colour.
void resolveColor(const Framebuffer& fb, Image& out);
/// Grey level = average sample depth (clear depth where nothing was drawn).
void resolveDepth(const Framebuffer& fb, Image& out);
/// The same depths, one float per pixel, row-major: what a depth-only pass (a shadow map)
/// reads back, without a four-channel image.
void resolveDepthPlane(const Framebuffer& fb, std::vector<float>& out);
/// A one-sample target's window depth per pixel in its own convention (reversed: 1 at the near
/// plane, 0 at the far), uncovered pixels at the far plane: what a shadow map reads. Unlike
/// resolveDepthPlane it does not turn reversed depth into standard (1 - d), which would cancel
/// the precision reversed depth keeps near 0.
void resolveWindowDepth(const Framebuffer& fb, std::vector<float>& out);
/// The depth view for people: each pixel's distance along the view axis, in the units of the
/// projection's near and far planes (depth 0 at nearPlane and 1 at farPlane in the standard
/// convention, as glm::perspectiveRH_ZO and orthoRH_ZO make it: falling like 1/distance for a
/// perspective projection, linear for an orthographic one), averaged over the samples a surface
/// covers; alpha is the covered fraction. Uncovered pixels are 0 with alpha 0.
void resolveViewDistance(const Framebuffer& fb, float nearPlane, float farPlane, Image& out, bool orthographic = false);
/// Heat map of depth-passing samples per pixel, normalised by the sample count.
/// Pixels where some sample holds a surface (its depth key is not the clear value): what a frame
/// covered, the denominator of "faces drawn per covered pixel" (issue 25's measure of waste).
uint64_t coveredPixels(const Framebuffer& fb);

/// The overdraw view's colour for a pixel where `layers` full layers of samples passed the depth
/// test (a ramp from dark blue through red and yellow to white at 8 and more); black for 0.
glm::vec3 overdrawColor(float layers);

/// The tiles view's colours of a block the coarse stage found fully covered, partly covered,
/// both (by different triangles) and never touched, before a quarter of the frame is mixed in.
inline const glm::vec3 kBlockFullColor{0.05f, 0.6f, 0.1f}, kBlockPartialColor{0.9f, 0.35f, 0.02f},
    kBlockBothColor{0.85f, 0.8f, 0.1f}, kBlockUntouchedColor{0.02f};

void visualizeOverdraw(const Framebuffer& fb, Image& out);
/// Each 8x8 block coloured by what the coarse stage decided for it: never touched, only
/// partial, only full, or both; the pixel grid of the colour image is dimmed underneath.
void visualizeBlockClasses(const Framebuffer& fb, const Image& color, Image& out);

}  // namespace cuberille::raster
