#include "raster/clip.h"

namespace cuberille::raster {
namespace {

float planeDistance(const glm::vec4& plane, const glm::vec4& p, int planeIndex) {
    float d = plane.x * p.x + plane.y * p.y + plane.z * p.z + plane.w * p.w;
    return planeIndex == ClipVolume::kMinWPlane ? d - kMinClipW : d;
}

ClipVertex intersect(const ClipVertex& inside, float dInside, const ClipVertex& outside,
                     float dOutside, int varyingCount) {
    const float t = dInside / (dInside - dOutside);
    ClipVertex r;
    r.position = inside.position + t * (outside.position - inside.position);
    for (int i = 0; i < varyingCount; ++i)
        r.varyings[i] = inside.varyings[i] + t * (outside.varyings[i] - inside.varyings[i]);
    return r;
}

ClipVolume guardBand(float xMin, float xMax, float yMin, float yMax) {
    ClipVolume v;
    v.planes[0] = {0, 0, 1, 0};      // near: z >= 0
    v.planes[1] = {0, 0, -1, 1};     // far: z <= w
    v.planes[2] = {0, 0, 0, 1};      // w >= kMinClipW
    v.planes[3] = {1, 0, 0, -xMin};  // x >= xMin * w
    v.planes[4] = {-1, 0, 0, xMax};  // x <= xMax * w
    v.planes[5] = {0, 1, 0, -yMin};
    v.planes[6] = {0, -1, 0, yMax};
    return v;
}

}  // namespace

ClipVolume ClipVolume::forViewport(int widthPixels, int heightPixels) {
    // Window x = (ndc + 1) * W / 2 stays within [-G, W + G] when |ndc| <= 1 + 2G / W.
    const float gx = 1.0f + 2.0f * kGuardBandPixels / static_cast<float>(widthPixels);
    const float gy = 1.0f + 2.0f * kGuardBandPixels / static_cast<float>(heightPixels);
    return guardBand(-gx, gx, -gy, gy);
}

ClipVolume ClipVolume::forWindowSpace(int widthPixels, int heightPixels) {
    return guardBand(-kGuardBandPixels, static_cast<float>(widthPixels + kGuardBandPixels),
                     -kGuardBandPixels, static_cast<float>(heightPixels + kGuardBandPixels));
}

uint32_t outcode(const ClipVolume& volume, const glm::vec4& position) {
    uint32_t code = 0;
    for (int k = 0; k < ClipVolume::kPlaneCount; ++k)
        if (!(planeDistance(volume.planes[k], position, k) >= 0.0f)) code |= 1u << k;
    return code;
}

ClipOutcome classifyTriangle(uint32_t code0, uint32_t code1, uint32_t code2) {
    if (code0 & code1 & code2) return ClipOutcome::Rejected;
    if ((code0 | code1 | code2) == 0) return ClipOutcome::Inside;
    return ClipOutcome::Clipped;
}

void clipTriangle(const ClipVolume& volume, uint32_t crossedPlanes, const ClipVertex& v0,
                  const ClipVertex& v1, const ClipVertex& v2, int varyingCount,
                  ClippedPolygon& out) {
    ClippedPolygon scratch;
    ClippedPolygon* src = &out;
    ClippedPolygon* dst = &scratch;
    src->count = 3;
    src->vertices[0] = v0, src->vertices[1] = v1, src->vertices[2] = v2;

    for (int k = 0; k < ClipVolume::kPlaneCount && src->count > 0; ++k) {
        if (!(crossedPlanes & (1u << k))) continue;
        const glm::vec4& plane = volume.planes[k];
        dst->count = 0;
        for (int i = 0; i < src->count; ++i) {
            const ClipVertex& a = src->vertices[i];
            const ClipVertex& b = src->vertices[(i + 1) % src->count];
            const float da = planeDistance(plane, a.position, k);
            const float db = planeDistance(plane, b.position, k);
            const bool aIn = da >= 0.0f, bIn = db >= 0.0f;
            if (aIn) dst->vertices[dst->count++] = a;
            if (aIn && !bIn) dst->vertices[dst->count++] = intersect(a, da, b, db, varyingCount);
            if (!aIn && bIn) dst->vertices[dst->count++] = intersect(b, db, a, da, varyingCount);
        }
        std::swap(src, dst);
    }
    if (src != &out) out = *src;
}

}  // namespace cuberille::raster
