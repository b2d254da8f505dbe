#pragma once
// Generated meshes for the benchmarks: a surface with detail everywhere, like a dense scan, at any
// triangle count, made by a command rather than stored.

#include <cmath>
#include <cstdint>

#include "scene/mesh.h"

namespace cuberille::bench {

/// A bumpy sphere of about n triangles (radius 1 with a 5% displacement).
inline scene::Mesh bumpySphere(uint64_t n) {
    const int s = std::max(8, int(std::sqrt(double(n) / 2.0)));
    scene::Mesh m;
    m.positions.reserve(size_t(s + 1) * size_t(s + 1));
    m.indices.reserve(size_t(s) * size_t(s) * 6);
    for (int j = 0; j <= s; ++j)
        for (int i = 0; i <= s; ++i) {
            const double u = 2.0 * M_PI * i / s, v = M_PI * j / s;
            const double r = 1.0 + 0.05 * std::sin(13.0 * u) * std::sin(11.0 * v);
            m.positions.push_back(glm::vec3(float(r * std::sin(v) * std::cos(u)), float(r * std::cos(v)),
                                            float(r * std::sin(v) * std::sin(u))));
        }
    for (int j = 0; j < s; ++j)
        for (int i = 0; i < s; ++i) {
            const uint32_t a = uint32_t(j * (s + 1) + i), b = a + 1, c = a + uint32_t(s + 1), d = c + 1;
            m.indices.insert(m.indices.end(), {a, c, b, b, c, d});
        }
    scene::computeVertexNormals(m);
    return m;
}

}  // namespace cuberille::bench
