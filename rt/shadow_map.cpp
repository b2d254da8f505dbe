#include "rt/shadow_map.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "raster/framebuffer.h"
#include "raster/parallel.h"
#include "raster/resolve.h"

namespace cuberille::rt {
namespace {

// An up vector not parallel to the view direction.
glm::vec3 upFor(const glm::vec3& forward) {
    return std::abs(forward.y) > 0.99f ? glm::vec3(0, 0, 1) : glm::vec3(0, 1, 0);
}

/// A directional light's view: looking along the light over the casters' bounds. With a focus,
/// the square it covers is narrowed to the part of the casters' extent the focus points span
/// across the light (plus `marginWorld` and two texels on every side): a receiver is shadowed
/// only by casters on its way to the light, which in this view lie over it. The depth range
/// stays the casters' whole one, so every caster between light and receiver is drawn.
ShadowMapFace orthographicFace(const glm::vec3& direction, const Aabb& bounds, std::span<const glm::vec3> focus,
                               float marginWorld, int size) {
    const glm::vec3 centre = bounds.centre();
    const float radius = std::max(0.5f * glm::length(bounds.extent()), 1e-6f);
    ShadowMapFace f;
    const glm::vec3 eye = centre - direction * (2.0f * radius);
    f.viewFromWorld = glm::lookAtRH(eye, centre, upFor(direction));
    f.nearPlane = 0.5f * radius;
    f.farPlane = 3.5f * radius;
    glm::vec2 lo(-radius), hi(radius);  // the casters' square in view x and y
    if (!focus.empty()) {
        glm::vec2 seenLo(std::numeric_limits<float>::max()), seenHi(std::numeric_limits<float>::lowest());
        for (const glm::vec3& p : focus) {
            const glm::vec2 v(f.viewFromWorld * glm::vec4(p, 1.0f));
            seenLo = glm::min(seenLo, v), seenHi = glm::max(seenHi, v);
        }
        seenLo -= marginWorld, seenHi += marginWorld;
        const glm::vec2 cutLo = glm::max(lo, seenLo), cutHi = glm::min(hi, seenHi);
        if (cutLo.x < cutHi.x && cutLo.y < cutHi.y) lo = cutLo, hi = cutHi;
    }
    const glm::vec2 middle = 0.5f * (lo + hi);
    float half = 0.5f * std::max(hi.x - lo.x, hi.y - lo.y);
    half = std::max(half * (1.0f + 4.0f / float(size)), 1e-6f);  // two texels more on each side
    f.halfExtent = half;
    f.clipFromWorld =
        glm::orthoRH_ZO(middle.x - half, middle.x + half, middle.y - half, middle.y + half, f.nearPlane, f.farPlane) *
        f.viewFromWorld;
    return f;
}

ShadowMapFace perspectiveFace(const glm::vec3& position, const glm::vec3& forward, float halfAngle, const Aabb& bounds) {
    ShadowMapFace f;
    f.perspective = true;
    f.viewFromWorld = glm::lookAtRH(position, position + forward, upFor(forward));
    float farthest = 0.0f;
    for (int c = 0; c < 8; ++c) {
        const glm::vec3 corner((c & 1) ? bounds.hi.x : bounds.lo.x, (c & 2) ? bounds.hi.y : bounds.lo.y,
                               (c & 4) ? bounds.hi.z : bounds.lo.z);
        farthest = std::max(farthest, glm::distance(position, corner));
    }
    f.farPlane = std::max(farthest * 1.01f, 1e-3f);
    f.nearPlane = f.farPlane * 1e-4f;
    f.halfExtent = std::tan(halfAngle);
    // Reversed depth (raster/framebuffer.h): the near plane lies 1e4 times nearer than the far one,
    // and standard depth's floats near 1 then resolve a receiver at the far end of a spot light
    // only to about a thousandth of its distance — coarser than the receiver bias of a 2048-texel
    // map, so hybrid shadowed lit receivers there. Reversed, a depth keeps float's relative
    // precision at every distance.
    f.clipFromWorld = raster::perspectiveProjection(2.0f * halfAngle, 1.0f, f.nearPlane, f.farPlane, raster::DepthConvention::Reversed) *
                      f.viewFromWorld;
    return f;
}

/// The viewport (x right, y down: DESIGN.md) folded into the face's projection, with the view's
/// depth axis as the third row: x = (clip.x / w + 1) size / 2 = (clip.x + w) size / 2 / w.
glm::mat4 texelTransform(const ShadowMapFace& f, int size) {
    auto row = [](const glm::mat4& m, int r) { return glm::vec4(m[0][r], m[1][r], m[2][r], m[3][r]); };
    const float half = 0.5f * float(size);
    const glm::vec4 clipX = row(f.clipFromWorld, 0), clipY = row(f.clipFromWorld, 1), clipW = row(f.clipFromWorld, 3);
    const glm::vec4 rows[4] = {half * (clipX + clipW), half * (clipW - clipY), -row(f.viewFromWorld, 2),
                               f.perspective ? clipW : glm::vec4(0.0f, 0.0f, 0.0f, 1.0f)};
    glm::mat4 t;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) t[c][r] = rows[r][c];
    return t;
}

/// Linear depth from the rasterizer's [0, 1] window depth: standard for orthographic faces,
/// reversed (1 at the near plane) for perspective ones (perspectiveFace).
float linearDepth(const ShadowMapFace& f, float d) {
    if (!f.perspective) return d >= 1.0f ? ShadowMap::kEmpty : f.nearPlane + d * (f.farPlane - f.nearPlane);
    if (!(d > 0.0f)) return ShadowMap::kEmpty;
    const double n = f.nearPlane, far = f.farPlane;
    return float(n * far / (n + double(d) * (far - n)));
}

/// An alpha-tested range drawn as the frame draws it, for depth alone: Unlit through the material's
/// alpha (its base colour texture made white, CasterAlphaTest::alphaOnly), cut at its cutoff, at
/// each texel's level of detail; both faces.
raster::DrawCall alphaTestedDraw(const ShadowMapFace& f, const TriangleMeshView& casters, const CasterRange& range,
                                 std::vector<uint32_t>& rebased) {
    const CasterAlphaTest& a = *range.alphaTest;
    const std::span<const uint32_t> indices = casters.indices.subspan(3 * size_t(range.firstTriangle), 3 * size_t(range.triangleCount));
    rebased.resize(indices.size());
    for (size_t i = 0; i < indices.size(); ++i) rebased[i] = indices[i] - range.firstVertex;
    raster::DrawCall d;
    d.space = raster::PositionSpace::Clip;
    d.clipFromObject = f.clipFromWorld;
    d.positions = casters.positions.subspan(range.firstVertex, range.vertexCount);
    d.indices = rebased;
    d.vertexAlphas = a.vertexAlphas;
    d.texCoords = a.texCoords;
    d.state = alphaTestedState(a);
    d.state.cull = raster::CullMode::None;  // both faces cast
    d.state.colorWriteMask = 0;
    return d;
}

void drawDepth(ShadowMapFace& f, const TriangleMeshView& casters, std::span<const CasterRange> ranges, int size,
               raster::Pipeline& gpu) {
    raster::FramebufferDesc desc;
    desc.widthPixels = desc.heightPixels = size;
    desc.samples = 1;
    desc.colorAttachment = false;  // depth only: nothing to allocate, clear or resolve for colour
    desc.depthConvention = f.perspective ? raster::DepthConvention::Reversed : raster::DepthConvention::Standard;
    gpu.beginFrame(desc);
    raster::DrawCall d;
    d.space = raster::PositionSpace::Clip;
    d.clipFromObject = f.clipFromWorld;
    d.positions = casters.positions;
    d.indices = casters.indices;
    d.state.shading = raster::ShadingModel::ConstantColor;
    d.state.cull = raster::CullMode::None;  // both faces cast
    d.state.colorWriteMask = 0;
    std::vector<std::vector<uint32_t>> rebased;  // alpha-tested ranges' indices, alive until the frame ends
    if (!anyAlphaTested(ranges)) {
        gpu.draw(d);
    } else {
        // Runs of opaque ranges as one draw each; an alpha-tested range through its alpha test,
        // its indices rebased to its first vertex.
        for (size_t r = 0; r < ranges.size();) {
            if (!ranges[r].alphaTest) {
                size_t end = r;
                while (end < ranges.size() && !ranges[end].alphaTest) ++end;
                const size_t first = 3 * size_t(ranges[r].firstTriangle);
                const size_t last = 3 * (size_t(ranges[end - 1].firstTriangle) + ranges[end - 1].triangleCount);
                d.indices = casters.indices.subspan(first, last - first);
                gpu.draw(d);
                r = end;
                continue;
            }
            gpu.draw(alphaTestedDraw(f, casters, ranges[r], rebased.emplace_back()));
            ++r;
        }
    }
    gpu.endFrame();
    raster::resolveWindowDepth(gpu.framebuffer(), f.depth);
    raster::parallelFor(size_t(size), [&](size_t y) {
        float* row = f.depth.data() + y * size_t(size);
        for (int x = 0; x < size; ++x) row[x] = linearDepth(f, row[x]);
    });
}

/// Whether two maps' faces project the world alike, every matrix and plane bit for bit.
bool sameProjections(const std::vector<ShadowMapFace>& a, const std::vector<ShadowMapFace>& b) {
    if (a.size() != b.size()) return false;
    for (size_t i = 0; i < a.size(); ++i)
        if (a[i].viewFromWorld != b[i].viewFromWorld || a[i].clipFromWorld != b[i].clipFromWorld ||
            a[i].texelFromWorld != b[i].texelFromWorld || a[i].perspective != b[i].perspective ||
            a[i].nearPlane != b[i].nearPlane || a[i].farPlane != b[i].farPlane || a[i].halfExtent != b[i].halfExtent)
            return false;
    return true;
}

}  // namespace

ShadowMap ShadowMap::render(const raster::Light& light, const TriangleMeshView& casters, const Aabb& bounds, int size,
                            raster::Pipeline& gpu, std::span<const glm::vec3> focus, float focusMarginWorld,
                            std::span<const CasterRange> ranges) {
    ShadowMap map;
    map.redraw(light, casters, bounds, size, gpu, focus, focusMarginWorld, 0, ranges);
    return map;
}

bool ShadowMap::redraw(const raster::Light& light, const TriangleMeshView& casters, const Aabb& bounds, int size,
                       raster::Pipeline& gpu, std::span<const glm::vec3> focus, float focusMarginWorld,
                       uint64_t castersVersion, std::span<const CasterRange> ranges) {
    std::vector<ShadowMapFace> faces;
    switch (light.type) {
        case raster::LightType::Directional:
            faces.push_back(orthographicFace(glm::normalize(light.direction), bounds, focus, focusMarginWorld, size));
            break;
        case raster::LightType::Spot: {
            const float halfAngle = std::min(std::acos(std::clamp(light.cosOuterCone, -1.0f, 1.0f)), glm::radians(85.0f));
            faces.push_back(perspectiveFace(light.position, glm::normalize(light.direction), halfAngle, bounds));
            break;
        }
        case raster::LightType::Point:
            for (const glm::vec3 axis : {glm::vec3(1, 0, 0), glm::vec3(-1, 0, 0), glm::vec3(0, 1, 0), glm::vec3(0, -1, 0),
                                         glm::vec3(0, 0, 1), glm::vec3(0, 0, -1)})
                faces.push_back(perspectiveFace(light.position, axis, glm::radians(45.0f), bounds));
            break;
    }
    for (ShadowMapFace& f : faces) f.texelFromWorld = texelTransform(f, size);
    if (castersVersion != 0 && castersVersion == castersVersion_ && size == size_ && light.position == lightPosition_ &&
        sameProjections(faces, faces_))
        return false;  // kept: the same casters seen through the same projections
    for (size_t i = 0; i < faces.size(); ++i) {
        ShadowMapFace& f = faces[i];
        if (i < faces_.size()) f.depth = std::move(faces_[i].depth);  // every texel is written below
        drawDepth(f, casters, ranges, size, gpu);
    }
    size_ = size;
    lightPosition_ = light.position;
    castersVersion_ = castersVersion;
    faces_ = std::move(faces);
    return true;
}

glm::vec3 ShadowMap::project(int face, const glm::vec3& p) const {
    const ShadowMapFace& f = faces_[size_t(face)];
    const glm::vec4 q = f.texelFromWorld * glm::vec4(p, 1.0f);
    if (!f.perspective) return glm::vec3(q);
    return {q.x / q.w, q.y / q.w, q.z};
}

ShadowMapTexel ShadowMap::locate(const glm::vec3& p) const {
    ShadowMapTexel t;
    int face = 0;
    if (faces_.size() == 6) {  // cube map: the face of the dominant axis from the light
        const glm::vec3 v = p - lightPosition_, a = glm::abs(v);
        const int axis = a.x >= a.y && a.x >= a.z ? 0 : (a.y >= a.z ? 1 : 2);
        face = 2 * axis + (v[axis] < 0.0f ? 1 : 0);
    }
    const glm::vec3 q = project(face, p);
    if (!(q.z > 0.0f) || !(q.x >= 0.0f && q.y >= 0.0f && q.x < float(size_) && q.y < float(size_))) return t;
    const ShadowMapFace& f = faces_[size_t(face)];
    t.face = face;
    t.x = int(q.x);
    t.y = int(q.y);
    t.position = glm::vec2(q);
    t.receiverDepth = q.z;
    t.texelWorld = 2.0f * f.halfExtent * (f.perspective ? q.z : 1.0f) / float(size_);
    return t;
}

}  // namespace cuberille::rt
