#pragma once
// The slow-but-sure rasterizer the pipeline is checked against: every sample of every pixel
// against every triangle, in exact integers, with the fill rule written the obvious way
// (geometrically: a top edge is horizontal with the third vertex below it; a left edge has the
// triangle's interior to its right). It shares nothing with raster/ but the snapping rule and
// the sample positions, which are the conventions under test's definition.

#include <cstdint>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "raster/sample_pattern.h"
#include "raster/setup.h"
#include "scene/tri_scene.h"

namespace cuberille::testing {

struct Point {
    int64_t x, y;  // subpixels
};

inline int64_t cross(Point o, Point a, Point b) {
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

/// Is edge a→b (of triangle a, b, c) a top or a left edge?
inline bool isTopOrLeft(Point a, Point b, Point c) {
    if (a.y == b.y) return c.y > a.y;  // horizontal: top when the third vertex is below
    // Non-horizontal: left when c lies right of the edge's line at c's height.
    const int64_t lhs = (c.x - a.x) * (b.y - a.y), rhs = (b.x - a.x) * (c.y - a.y);
    return (b.y > a.y) ? lhs > rhs : lhs < rhs;
}

inline bool sampleCovered(Point a, Point b, Point c, Point p) {
    const int64_t area = cross(a, b, c);
    if (area == 0) return false;
    if (area < 0) std::swap(b, c);  // now every edge has the interior at cross > 0
    const Point v[3] = {a, b, c};
    for (int i = 0; i < 3; ++i) {
        const Point s = v[i], e = v[(i + 1) % 3], o = v[(i + 2) % 3];
        const int64_t w = cross(s, e, p);
        if (w < 0) return false;
        if (w == 0 && !isTopOrLeft(s, e, o)) return false;
    }
    return true;
}

struct ReferenceImage {
    int width, height, samples;
    std::vector<glm::vec4> values;  // ((y * width) + x) * samples + s

    const glm::vec4& at(int x, int y, int s) const {
        return values[(size_t(y) * width + x) * samples + s];
    }
};

inline ReferenceImage referenceRasterize(const scene::TriScene& scene, int width, int height,
                                         int samples) {
    const raster::SamplePattern& sp = raster::standardSamplePattern(samples);
    ReferenceImage img{width, height, samples,
                       std::vector<glm::vec4>(size_t(width) * height * samples, glm::vec4(0.0f))};
    for (size_t t = 0; t < scene.triangleCount(); ++t) {
        Point v[3];
        for (int k = 0; k < 3; ++k)
            v[k] = {raster::snapToSubpixels(scene.positions[t * 3 + k].x),
                    raster::snapToSubpixels(scene.positions[t * 3 + k].y)};
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                for (int s = 0; s < samples; ++s) {
                    const Point p{x * 256 + 128 + sp.dx[s] * 16, y * 256 + 128 + sp.dy[s] * 16};
                    if (sampleCovered(v[0], v[1], v[2], p))
                        img.values[(size_t(y) * width + x) * samples + s] = scene.colors[t];
                }
    }
    return img;
}

}  // namespace cuberille::testing
