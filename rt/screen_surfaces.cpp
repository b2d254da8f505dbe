#include "rt/screen_surfaces.h"

#include "raster/parallel.h"
#include "raster/pipeline.h"
#include "raster/resolve.h"

namespace cuberille::rt {
namespace {

// Triangle ids as flat colours: r = 1 marks a surface, g and b hold the id's low and high 16 bits,
// each exactly representable in float and copied unchanged through ConstantColor and a
// one-sample resolve.
glm::vec4 idColor(uint32_t id) { return {1.0f, float(id & 0xFFFFu), float(id >> 16), 1.0f}; }
uint32_t idFrom(const float* rgba) { return uint32_t(rgba[1]) | (uint32_t(rgba[2]) << 16); }

}  // namespace

ScreenSurfaces findScreenSurfaces(const TriangleMeshView& casters, std::span<const CasterRange> ranges,
                                  const glm::mat4& clipFromWorld, int width, int height) {
    std::vector<glm::vec4> colors(casters.triangleCount());
    for (uint32_t t = 0; t < colors.size(); ++t) colors[t] = idColor(t);
    raster::Pipeline pipeline;
    raster::FramebufferDesc desc;
    desc.widthPixels = width;
    desc.heightPixels = height;
    desc.samples = 1;
    pipeline.beginFrame(desc);
    // Each range is drawn over its own vertices (as the scene draws its mesh), so the vertex
    // stage shades each vertex once: indices are rebased to the range's first vertex.
    std::vector<uint32_t> local(casters.indices.begin(), casters.indices.end());
    for (const CasterRange& r : ranges)
        for (size_t i = size_t(r.firstTriangle) * 3; i < size_t(r.firstTriangle + r.triangleCount) * 3; ++i)
            local[i] -= r.firstVertex;
    for (const CasterRange& r : ranges) {
        raster::DrawCall d;
        d.space = raster::PositionSpace::Clip;
        d.clipFromObject = clipFromWorld;
        d.positions = casters.positions.subspan(r.firstVertex, r.vertexCount);
        d.indices = std::span<const uint32_t>(local).subspan(size_t(r.firstTriangle) * 3, size_t(r.triangleCount) * 3);
        d.triangleColors = std::span<const glm::vec4>(colors).subspan(r.firstTriangle, r.triangleCount);
        d.state.shading = raster::ShadingModel::ConstantColor;
        d.state.cull = r.cull;
        pipeline.draw(d);
    }
    pipeline.endFrame();
    raster::Image ids;
    raster::resolveColor(pipeline.framebuffer(), ids);

    ScreenSurfaces s;
    s.width = width;
    s.height = height;
    const size_t pixels = size_t(width) * height;
    s.triangle.assign(pixels, ScreenSurfaces::kNone);
    s.position.assign(pixels, glm::vec3(0.0f));
    s.normal.assign(pixels, glm::vec3(0.0f));
    const glm::mat4 worldFromClip = glm::inverse(clipFromWorld);
    raster::parallelFor(size_t(height), [&](size_t y) {
        for (int x = 0; x < width; ++x) {
            const size_t i = y * width + x;
            const float* rgba = ids.pixel(x, int(y));
            if (rgba[0] != 1.0f) continue;
            const uint32_t t = idFrom(rgba);
            // The camera ray through the pixel centre, from the near to the far plane.
            const float nx = (float(x) + 0.5f) / float(width) * 2.0f - 1.0f;
            const float ny = 1.0f - (float(y) + 0.5f) / float(height) * 2.0f;
            const glm::vec4 n4 = worldFromClip * glm::vec4(nx, ny, 0.0f, 1.0f);
            const glm::vec4 f4 = worldFromClip * glm::vec4(nx, ny, 1.0f, 1.0f);
            const glm::vec3 origin = glm::vec3(n4) / n4.w, direction = glm::vec3(f4) / f4.w - origin;
            const glm::vec3 a = casters.vertex(t, 0), b = casters.vertex(t, 1), c = casters.vertex(t, 2);
            glm::vec3 normal = glm::cross(b - a, c - a);
            const float length = glm::length(normal);
            const float denominator = glm::dot(normal, direction);
            if (!(length > 0.0f) || denominator == 0.0f) continue;  // degenerate or edge-on: no surface
            normal /= length;
            s.triangle[i] = t;
            s.position[i] = origin + direction * (glm::dot(normal * length, a - origin) / denominator);
            s.normal[i] = denominator > 0.0f ? -normal : normal;
        }
    });
    return s;
}

}  // namespace cuberille::rt
