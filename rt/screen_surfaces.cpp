#include "rt/screen_surfaces.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "raster/parallel.h"
#include "raster/texture.h"

namespace cuberille::rt {
namespace {

// Triangle ids as flat colours: r = 1 marks a surface, g and b hold the id's low and high 16 bits,
// each exactly representable in float and copied unchanged through ConstantColor.
// An alpha-tested range's ids come through the Unlit shade stage as three equal vertex colours
// interpolated, off by a few ulps of 65535 at most (2e-2), so they are rounded back.
glm::vec4 idColor(uint32_t id) { return {1.0f, float(id & 0xFFFFu), float(id >> 16), 1.0f}; }
uint32_t idFrom(const glm::vec4& c) {
    // Both halves are below 2^16, where adding one half is exact: the nearest integer, truncated.
    return c.r > 0.5f ? uint32_t(c.g + 0.5f) | (uint32_t(c.b + 0.5f) << 16) : ScreenSurfaces::kNone;
}

/// Each pixel's id read straight from the one-sample colour tiles (no resolved image); returns
/// the farthest window depth of a pixel with an id (-1: none).
float readIds(const raster::Framebuffer& fb, std::vector<uint32_t>& ids) {
    ids.assign(size_t(fb.width()) * fb.height(), ScreenSurfaces::kNone);
    std::vector<float> farthest(size_t(fb.tileCount()), -1.0f);  // per tile, taken in tile order: exact anyway
    raster::parallelFor(size_t(fb.tileCount()), [&](size_t tile) {
        if (!fb.tileTouched(int(tile))) return;
        const glm::vec4* color = fb.tileColor(int(tile));
        const float* depth = fb.tileDepth(int(tile));
        const int x0 = int(tile) % fb.tilesX() * raster::kTileSizePixels, y0 = int(tile) / fb.tilesX() * raster::kTileSizePixels;
        const int x1 = std::min(fb.width(), x0 + raster::kTileSizePixels), y1 = std::min(fb.height(), y0 + raster::kTileSizePixels);
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
                const int i = (y - y0) * raster::kTileSizePixels + (x - x0);
                const uint32_t id = idFrom(color[i]);
                ids[size_t(y) * fb.width() + x] = id;
                if (id != ScreenSurfaces::kNone) farthest[tile] = std::max(farthest[tile], depth[i]);
            }
    });
    return *std::max_element(farthest.begin(), farthest.end());
}

/// The plane through a, b, c (zero normal where they span no area), by moveCasters' arithmetic.
TrianglePlane planeThrough(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
    const glm::vec3 normal = glm::cross(b - a, c - a);
    const float length = glm::length(normal);
    if (!(length > 0.0f) || !std::isfinite(length)) return {};  // degenerate: no surface
    TrianglePlane plane;
    plane.normal = normal / length;
    plane.offset = glm::dot(plane.normal, a);
    return plane;
}

/// Vertex k of triangle t of a draw, in world space (unchanged where worldFromObject is the
/// identity, so the plane has the casters' bits).
glm::vec3 worldVertex(const raster::DrawCall& d, uint32_t t, int k, bool identity) {
    const uint32_t v = d.indices.empty() ? 3 * t + uint32_t(k) : d.indices[3 * size_t(t) + size_t(k)];
    const glm::vec3 p = d.positions[v];
    return identity ? p : glm::vec3(d.worldFromObject * glm::vec4(p, 1.0f));
}

/// How far ahead surfacesFromVisibility asks for a pixel's vertices (its indices twice as far).
constexpr int kPrefetchPixels = 16;

/// The frustum's corners from the near plane to window depth `farthest` (standard convention).
std::vector<glm::vec3> frustumCorners(const glm::mat4& worldFromClip, float farthest) {
    std::vector<glm::vec3> corners;
    for (const float z : {0.0f, farthest})
        for (const float y : {-1.0f, 1.0f})
            for (const float x : {-1.0f, 1.0f}) {
                const glm::vec4 p = worldFromClip * glm::vec4(x, y, z, 1.0f);
                corners.push_back(glm::vec3(p) / p.w);
            }
    return corners;
}

}  // namespace

ScreenSurfaces::CameraRow ScreenSurfaces::cameraRow(int y) const {
    // Clip-space x of pixel x's centre is (x + 1/2) 2 / width - 1, affine in x: the row's points
    // are the worldFromClip product at x = 0 plus x steps of its first column.
    const float ndcPerPixelX = 2.0f / float(width);
    const float nx = 0.5f * ndcPerPixelX - 1.0f;
    const float ny = 1.0f - (float(y) + 0.5f) / float(height) * 2.0f;
    CameraRow row;
    row.firstPixel = size_t(y) * size_t(width);
    row.nearAtLeft = worldFromClip[0] * nx + worldFromClip[1] * ny + worldFromClip[3];
    row.nearPerPixel = worldFromClip[0] * ndcPerPixelX;
    row.nearToFar = worldFromClip[2];
    return row;
}

std::shared_ptr<const raster::Texture> alphaTestTexture(const raster::Texture& t) {
    const int w = t.width(), h = t.height();
    if (t.format() == raster::TexelFormat::LinearFloat) {
        std::vector<glm::vec4> rgba(size_t(w) * size_t(h));
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) rgba[size_t(y) * w + x] = {1.0f, 1.0f, 1.0f, t.texel(0, x, y).a};
        return std::make_shared<raster::Texture>(w, h, std::move(rgba), t.wrapU(), t.wrapV(), t.filter());
    }
    // The mip chain is built again from level 0 by the same box filter, a channel at a time, so
    // every level's alpha bytes are the original's.
    const std::vector<uint32_t> packed = t.packedRows(0);
    std::vector<uint8_t> bytes(4 * packed.size());
    for (size_t i = 0; i < packed.size(); ++i) {
        bytes[4 * i] = bytes[4 * i + 1] = bytes[4 * i + 2] = 255;
        bytes[4 * i + 3] = uint8_t(packed[i] >> 24);
    }
    return std::make_shared<raster::Texture>(w, h, bytes, t.format(), t.wrapU(), t.wrapV(), t.filter());
}

void VisibilityBuffer::setCasters(const TriangleMeshView& casters, std::span<const CasterRange> ranges) {
    ranges_.assign(ranges.begin(), ranges.end());
    const size_t triangles = casters.triangleCount();
    idColors_.resize(triangles);
    for (uint32_t t = 0; t < triangles; ++t) idColors_[t] = idColor(t);
    // Each range is drawn over its own vertices (as the scene draws its mesh), so the vertex
    // stage shades each vertex once: indices are rebased to the range's first vertex.
    rangeIndices_.assign(casters.indices.begin(), casters.indices.end());
    for (const CasterRange& r : ranges)
        for (size_t i = size_t(r.firstTriangle) * 3; i < size_t(r.firstTriangle + r.triangleCount) * 3; ++i)
            rangeIndices_[i] -= r.firstVertex;
    // Alpha-tested ranges, unindexed: per corner its triangle's id, alpha and texture coordinates.
    masked_.clear();
    for (size_t k = 0; k < ranges.size(); ++k) {
        const CasterRange& r = ranges[k];
        if (!r.alphaTest) continue;
        const CasterAlphaTest& a = *r.alphaTest;
        MaskedRange m;
        m.range = k;
        for (uint32_t t = r.firstTriangle; t < r.firstTriangle + r.triangleCount; ++t)
            for (int corner = 0; corner < 3; ++corner) {
                const uint32_t v = rangeIndices_[3 * size_t(t) + size_t(corner)];
                m.ids.push_back(glm::vec3(idColor(t)));
                if (!a.vertexAlphas.empty()) m.alphas.push_back(a.vertexAlphas[v]);
                if (a.alphaOnly && !a.texCoords.empty()) m.texCoords.push_back(a.texCoords[v]);
            }
        masked_.push_back(std::move(m));
    }
    moveCasters(casters);
}

void VisibilityBuffer::expandMaskedPositions() {
    for (MaskedRange& m : masked_) {
        const CasterRange& r = ranges_[m.range];
        m.positions.resize(size_t(r.triangleCount) * 3);
        for (size_t i = 0; i < m.positions.size(); ++i)
            m.positions[i] = casters_.positions[casters_.indices[size_t(r.firstTriangle) * 3 + i]];
    }
}

void VisibilityBuffer::moveCasters(const TriangleMeshView& casters) {
    casters_ = casters;
    expandMaskedPositions();
    const size_t triangles = casters.triangleCount();
    std::vector<TrianglePlane>& planes = surfaces_.planes;
    planes.assign(triangles, TrianglePlane{});
    raster::parallelFor((triangles + 4095) / 4096, [&](size_t chunk) {
        for (size_t t = chunk * 4096; t < std::min(triangles, (chunk + 1) * 4096); ++t) {
            planes[t] = planeThrough(casters.vertex(t, 0), casters.vertex(t, 1), casters.vertex(t, 2));
        }
    });
}

const ScreenSurfaces& VisibilityBuffer::draw(const glm::mat4& clipFromWorld, int width, int height, raster::Pipeline& gpu) {
    raster::FramebufferDesc desc;
    desc.widthPixels = width;
    desc.heightPixels = height;
    desc.samples = 1;
    gpu.beginFrame(desc);
    auto masked = masked_.begin();
    for (size_t k = 0; k < ranges_.size(); ++k) {
        const CasterRange& r = ranges_[k];
        if (r.triangleCount == 0) {  // a mesh without triangles: a draw of no indices would be an unindexed one
            if (masked != masked_.end() && masked->range == k) ++masked;
            continue;
        }
        if (masked != masked_.end() && masked->range == k) {
            gpu.draw(maskedDraw(*masked++, clipFromWorld));
            continue;
        }
        raster::DrawCall d;
        d.space = raster::PositionSpace::Clip;
        d.clipFromObject = clipFromWorld;
        d.positions = casters_.positions.subspan(r.firstVertex, r.vertexCount);
        d.indices = std::span<const uint32_t>(rangeIndices_).subspan(size_t(r.firstTriangle) * 3, size_t(r.triangleCount) * 3);
        d.triangleColors = std::span<const glm::vec4>(idColors_).subspan(r.firstTriangle, r.triangleCount);
        d.state.shading = raster::ShadingModel::ConstantColor;
        d.state.cull = r.cull;
        gpu.draw(d);
    }
    gpu.endFrame();

    ScreenSurfaces& s = surfaces_;
    s.width = width;
    s.height = height;
    s.worldFromClip = glm::inverse(clipFromWorld);
    const float farthest = readIds(gpu.framebuffer(), s.triangle);
    s.seenHull.clear();
    if (farthest >= 0.0f) s.seenHull = frustumCorners(s.worldFromClip, farthest);
    return s;
}

void VisibilityBuffer::seenByRange(raster::VisibilityBuffer& out) const {
    const ScreenSurfaces& s = surfaces_;
    out.width = s.width, out.height = s.height, out.samples = 1;
    out.draw.resize(s.triangle.size());
    out.triangle.resize(s.triangle.size());
    // Neighbouring pixels mostly see one range, so a pixel first tries the range the pixel before
    // it in its row found, and searches only when that misses; the ranges are in triangle order
    // (an empty one shares its first triangle with the next, and the search takes the last range
    // that starts at or below t).
    raster::parallelFor(size_t(s.height), [&](size_t y) {
        uint32_t k = 0;
        for (size_t i = y * size_t(s.width); i < (y + 1) * size_t(s.width); ++i) {
            const uint32_t t = s.triangle[i];
            if (t == ScreenSurfaces::kNone) {
                out.draw[i] = out.triangle[i] = raster::VisibilityBuffer::kNone;
                continue;
            }
            const CasterRange* r = &ranges_[k];
            if (t < r->firstTriangle || t >= r->firstTriangle + r->triangleCount) {
                const auto after = std::upper_bound(ranges_.begin(), ranges_.end(), t,
                                                    [](uint32_t id, const CasterRange& c) { return id < c.firstTriangle; });
                k = uint32_t(after - ranges_.begin()) - 1;
                r = &ranges_[k];
            }
            out.draw[i] = k;
            out.triangle[i] = t - r->firstTriangle;
        }
    });
}

void surfacesFromVisibility(const raster::VisibilityBuffer& centres, std::span<const raster::DrawCall> draws,
                            const glm::mat4& clipFromWorld, ScreenSurfaces& s) {
    if (centres.samples != 1) throw std::invalid_argument("surfacesFromVisibility: one sample a pixel (its centre)");
    s.width = centres.width;
    s.height = centres.height;
    s.worldFromClip = glm::inverse(clipFromWorld);
    const size_t pixels = size_t(s.width) * size_t(s.height);
    s.triangle.assign(pixels, ScreenSurfaces::kNone);
    s.planes.resize(pixels);
    std::vector<uint8_t> identity(draws.size());
    for (size_t d = 0; d < draws.size(); ++d) identity[d] = draws[d].worldFromObject == glm::mat4(1.0f);
    // Per row, the farthest window depth of a surface seen (-1: none); the largest of them is
    // exact in any order.
    std::vector<float> farthest(size_t(s.height), -1.0f);
    // A scan's triangles are scattered over megabytes, so each pixel's index and vertex reads
    // miss the cache: the indices are asked for two strides ahead and, once there, the vertices
    // one stride ahead, so the misses overlap (the dragon at 1280x720: 20 -> 13-16 ms).
    const auto prefetchIndices = [&](size_t i) {
        const uint32_t d = centres.draw[i];
        if (d != raster::VisibilityBuffer::kNone && !draws[d].indices.empty())
            __builtin_prefetch(&draws[d].indices[3 * size_t(centres.triangle[i])]);
    };
    const auto prefetchVertices = [&](size_t i) {
        const uint32_t d = centres.draw[i];
        if (d == raster::VisibilityBuffer::kNone) return;
        const raster::DrawCall& call = draws[d];
        const uint32_t t = centres.triangle[i];
        for (int k = 0; k < 3; ++k)
            __builtin_prefetch(&call.positions[call.indices.empty() ? 3 * size_t(t) + k : call.indices[3 * size_t(t) + k]]);
    };
    raster::parallelFor(size_t(s.height), [&](size_t y) {
        const ScreenSurfaces::CameraRow row = s.cameraRow(int(y));
        for (int x = 0; x < s.width; ++x) {
            const size_t i = row.firstPixel + size_t(x);
            if (x + 2 * kPrefetchPixels < s.width) prefetchIndices(i + 2 * kPrefetchPixels);
            if (x + kPrefetchPixels < s.width) prefetchVertices(i + kPrefetchPixels);
            const uint32_t d = centres.draw[i];
            if (d == raster::VisibilityBuffer::kNone) continue;
            const uint32_t t = centres.triangle[i];
            const raster::DrawCall& call = draws[d];
            s.planes[i] = planeThrough(worldVertex(call, t, 0, identity[d]), worldVertex(call, t, 1, identity[d]),
                                       worldVertex(call, t, 2, identity[d]));
            s.triangle[i] = uint32_t(i);
            Surface surface;
            if (!s.surfaceAt(row, x, surface)) continue;
            const glm::vec4 clip = clipFromWorld * glm::vec4(surface.position, 1.0f);
            farthest[y] = std::max(farthest[y], clip.z / clip.w);
        }
    });
    const float deepest = *std::max_element(farthest.begin(), farthest.end());
    s.seenHull.clear();
    if (deepest >= 0.0f) s.seenHull = frustumCorners(s.worldFromClip, std::min(deepest, 1.0f));
}

void centresWhereSamplesAgree(const raster::VisibilityBuffer& samples, raster::VisibilityBuffer& centres,
                              std::vector<uint32_t>& open) {
    const int S = samples.samples;
    centres.reset(samples.width, samples.height, 1);
    // Rows in parallel, each listing its own open pixels; joined in row order.
    std::vector<std::vector<uint32_t>> openInRow(size_t(samples.height));
    raster::parallelFor(size_t(samples.height), [&](size_t y) {
        for (size_t p = y * size_t(samples.width); p < (y + 1) * size_t(samples.width); ++p) {
            const size_t first = p * size_t(S);
            bool agree = true;
            for (int s = 1; s < S && agree; ++s)
                agree = samples.draw[first + s] == samples.draw[first] && samples.triangle[first + s] == samples.triangle[first];
            if (!agree) {
                openInRow[y].push_back(uint32_t(p));
                continue;
            }
            centres.draw[p] = samples.draw[first];
            centres.triangle[p] = samples.triangle[first];
        }
    });
    open.clear();
    for (const std::vector<uint32_t>& row : openInRow) open.insert(open.end(), row.begin(), row.end());
}

// An alpha-tested range as the frame's alpha test sees it: Unlit, white (the id is the vertex
// colour, times a white factor and a white texture), with the material's alpha and cutoff.
raster::DrawCall VisibilityBuffer::maskedDraw(const MaskedRange& m, const glm::mat4& clipFromWorld) const {
    const CasterRange& r = ranges_[m.range];
    const CasterAlphaTest& a = *r.alphaTest;
    raster::DrawCall d;
    d.space = raster::PositionSpace::Clip;
    d.clipFromObject = clipFromWorld;
    d.positions = m.positions;
    d.vertexColors = m.ids;
    d.vertexAlphas = m.alphas;
    d.texCoords = m.texCoords;
    d.state = alphaTestedState(a);
    d.state.cull = r.cull;
    return d;
}

ScreenSurfaces findScreenSurfaces(const TriangleMeshView& casters, std::span<const CasterRange> ranges,
                                  const glm::mat4& clipFromWorld, int width, int height, raster::Pipeline& gpu) {
    VisibilityBuffer buffer;
    buffer.setCasters(casters, ranges);
    return buffer.draw(clipFromWorld, width, height, gpu);
}

}  // namespace cuberille::rt
