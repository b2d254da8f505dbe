#include "rt/shadows.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <utility>

#include "raster/clock.h"
#include "raster/parallel.h"
#include "rt/ambient_occlusion.h"
#include "rt/ray_query.h"
#include "rt/shadow_map.h"
#include "rt/shadow_mode_choice.h"
#include "rt/wide_bvh.h"

namespace cuberille::rt {
namespace shadow_detail {

/// A map face's marks for the hybrid method.
struct FaceMarks {
    // Per texel, the nearest thin caster's depth at its centre, as the map would have stored
    // it; +inf: none.
    std::vector<float> thinDepth;
    // A min pyramid of discontinuity depths: level 0 holds, per texel, the near side's depth
    // of a discontinuity there (+inf: none); each level above the minimum of 2x2 below.
    std::vector<std::vector<float>> discontinuityDepth;
    std::vector<int> levelSize;
    float nearestDepth = 0.0f;  // the nearest caster depth in the face
};

/// The thin-caster marking's working space, used by each face of a map in turn.
struct ThinMarkingScratch {
    std::vector<glm::vec3> projected;     // per caster vertex: texel x, texel y, linear depth
    std::vector<int8_t> facing;           // per caster triangle: its side toward the light
    std::vector<uint8_t> nearSilhouette;  // per position id
};

}  // namespace shadow_detail

struct LightShadowStorage {
    ShadowMap map;
    std::vector<shadow_detail::FaceMarks> faces;  // per face of the map (hybrid, soft)
    shadow_detail::ThinMarkingScratch scratch;
    /// What `faces` were made from `map` with; empty when they are not the map's (it was drawn since).
    std::optional<ShadowOptions> marksOptions;
};

void LightShadowStorageDelete::operator()(LightShadowStorage* storage) const { delete storage; }

namespace {

using shadow_detail::FaceMarks;
using shadow_detail::ThinMarkingScratch;

// A soft shadow's silhouette lies within a texel of the discontinuity texels either side of it (it
// passes between two adjacent texel centres that disagree); a sixteenth more covers rounding.
constexpr float kPenumbraEdgeSlackTexels = 1.0f + 1.0f / 16.0f;

// ---- the light as seen from a surface point ------------------------------------------------

struct Incidence {
    glm::vec3 toLight{0.0f};  // unit
    float distance = 0.0f;    // +inf for directional lights
    bool reaches = false;     // the light can contribute here at all (facing, in cone, in range)
};

/// `toSun`: a directional light's unit direction toward it, the same at every receiver.
Incidence incidence(const raster::Light& light, const glm::vec3& toSun, const glm::vec3& p, const glm::vec3& n) {
    Incidence in;
    if (light.type == raster::LightType::Directional) {
        in.toLight = toSun;
        in.distance = std::numeric_limits<float>::infinity();
    } else {
        const glm::vec3 d = light.position - p;
        in.distance = glm::length(d);
        if (!(in.distance > 0.0f)) return in;
        in.toLight = d / in.distance;
        if (light.range > 0.0f && in.distance >= light.range) return in;
        if (light.type == raster::LightType::Spot && glm::dot(light.direction, -in.toLight) <= light.cosOuterCone) return in;
    }
    in.reaches = glm::dot(n, in.toLight) > 0.0f;
    return in;
}

float squaredDistanceToSegment(const glm::vec2& p, const glm::vec2& a, const glm::vec2& b) {
    const glm::vec2 ab = b - a;
    const float length2 = glm::dot(ab, ab);
    const float t = length2 > 0.0f ? std::clamp(glm::dot(p - a, ab) / length2, 0.0f, 1.0f) : 0.0f;
    const glm::vec2 d = p - (a + t * ab);
    return glm::dot(d, d);
}

/// Whether p lies inside a 2D triangle (either winding) or within sqrt(reach2) of its edges.
bool withinReachOfTriangle(const glm::vec2& p, const glm::vec2& a, const glm::vec2& b, const glm::vec2& c, float reach2) {
    auto side = [](const glm::vec2& u, const glm::vec2& v, const glm::vec2& w) {
        return (v.x - u.x) * (w.y - u.y) - (v.y - u.y) * (w.x - u.x);
    };
    const float d0 = side(a, b, p), d1 = side(b, c, p), d2 = side(c, a, p);
    if ((d0 >= 0 && d1 >= 0 && d2 >= 0) || (d0 <= 0 && d1 <= 0 && d2 <= 0)) return true;
    return squaredDistanceToSegment(p, a, b) <= reach2 || squaredDistanceToSegment(p, b, c) <= reach2 ||
           squaredDistanceToSegment(p, c, a) <= reach2;
}

/// target = min(target, value), atomically: the result is the same whichever thread is first.
void keepMinimum(float& target, float value) {
    std::atomic_ref<float> slot(target);
    float current = slot.load(std::memory_order_relaxed);
    while (value < current && !slot.compare_exchange_weak(current, value, std::memory_order_relaxed)) {
    }
}


/// Levels of a min pyramid over size x size texels, halved (rounding up) down to one.
int pyramidLevels(int size) {
    int levels = 1;
    for (; size > 1; size = (size + 1) / 2) ++levels;
    return levels;
}

// ---- one light's shadow stage ------------------------------------------------------------

class LightShadows {
public:
    /// Draws into `storage`, whatever an earlier frame left there.
    LightShadows(const raster::Light& light, const ShadowCasters& casters, const ShadowOptions& options, raster::Pipeline& gpu,
                 LightShadowStorage& storage)
        : light_(light), casters_(casters), options_(options), gpu_(gpu), map_(storage.map), faces_(storage.faces),
          scratch_(storage.scratch), marksOptions_(storage.marksOptions) {
        rayOffset_ = surfaceRayOffset(casters.bounds);
        if (options.soft) disk_ = diskSamples(std::max(1, options.softSamplesPerSide));
    }

    /// The map, focused on the receivers in view (MapFocus::View) or over every caster (Scene);
    /// soft shadows widen a focus by how far sideways a ray to the light's disk can stray over the
    /// casters' depth (their bounding sphere's diameter). Returns whether the map was drawn
    /// (false: kept from the last frame, and with it the marks, which depend on nothing else:
    /// the map, the casters and the options).
    bool prepareMap(const ScreenSurfaces& surfaces) {
        const bool drawn = map_.redraw(light_, casters_.mesh, casters_.bounds, options_.mapSizeTexels, gpu_, focus(surfaces),
                                       focusMargin(), casters_.version, casters_.ranges);
        if (drawn) marksOptions_.reset();
        if (options_.mode != ShadowMode::Hybrid && !options_.soft) return drawn;
        if (marksOptions_ && sameMarkingOptions(*marksOptions_, options_)) return drawn;
        faces_.resize(size_t(map_.faceCount()));
        for (int f = 0; f < map_.faceCount(); ++f) prepareFace(f);
        marksOptions_ = options_;
        return drawn;
    }

    std::span<const glm::vec3> focus(const ScreenSurfaces& surfaces) const {
        return options_.focus == MapFocus::View ? std::span<const glm::vec3>(surfaces.seenHull) : std::span<const glm::vec3>();
    }
    float focusMargin() const { return options_.soft ? options_.lightRadius * glm::length(casters_.bounds.extent()) : 0.0f; }

    static bool sameMarkingOptions(const ShadowOptions& a, const ShadowOptions& b) {
        return a.mode == b.mode && a.soft == b.soft && a.lightRadius == b.lightRadius && a.mapSizeTexels == b.mapSizeTexels &&
               a.focus == b.focus;
    }

    /// The light's visibility at one receiver; sets *marked when rays decided it, adds rays.
    float visibility(const glm::vec3& p, const glm::vec3& n, const Incidence& in, bool* marked, uint64_t* rays) const {
        *marked = false;
        if (options_.mode == ShadowMode::RayTraced) {
            *marked = true;
            return trace(p, n, in, rays);
        }
        const ShadowMapTexel t = map_.locate(p);
        if (t.face < 0) {  // outside the map: only rays can tell
            if (options_.mode == ShadowMode::Map) return 1.0f;
            *marked = true;
            return trace(p, n, in, rays);
        }
        const Receiver r = receiver(p, n, t);
        if (options_.mode == ShadowMode::Map) return options_.soft ? percentageCloser(r, t) : (litAt(r, t, 0, 0) ? 1.0f : 0.0f);
        int decision = 0;  // hybrid: what the 3x3 texels agree on, or -1
        if (potentiallyIncorrect(r, t, &decision)) {
            *marked = true;
            return trace(p, n, in, rays);
        }
        return float(decision);
    }

    /// Whether hard ray-traced shadows go a tile at a time (traceTileAsPacket): through the grid's
    /// packets, or the wide BVH's (the dragon on its ground, 1280x720: mask 24.7 ms ray by ray,
    /// 20.7 ms as packets).
    bool tracesTilesAsPackets() const { return options_.mode == ShadowMode::RayTraced && !options_.soft; }

    /// Hard ray-traced shadows for the kPacketTilePixels-square tile at (x0, y0):
    /// its receivers' rays toward the light as one packet (for a directional light, parallel
    /// rays: Wald et al.'s shadow packets). Each ray's answer is its single query's, so the mask,
    /// marks and counts (receivers, marked, rays) are those visibility() gives pixel by pixel.
    void traceTileAsPacket(const ScreenSurfaces& surfaces, int x0, int y0, const glm::vec3& toSun, std::vector<float>& mask,
                           std::vector<uint8_t>& marked, std::array<uint64_t, 3>& counts) const {
        Ray packet[kPacketTilePixels * kPacketTilePixels];
        size_t pixel[kPacketTilePixels * kPacketTilePixels];
        uint8_t occludedRays[kPacketTilePixels * kPacketTilePixels];
        size_t n = 0;
        for (int y = y0; y < std::min(y0 + kPacketTilePixels, surfaces.height); ++y) {
            const ScreenSurfaces::CameraRow row = surfaces.cameraRow(y);
            for (int x = x0; x < std::min(x0 + kPacketTilePixels, surfaces.width); ++x) {
                const size_t i = row.firstPixel + size_t(x);
                Surface surface;
                if (!surfaces.covered(i) || !surfaces.surfaceAt(row, x, surface)) continue;
                const Incidence in = incidence(light_, toSun, surface.position, surface.normal);
                if (!in.reaches) {
                    mask[i] = 0.0f;
                    continue;
                }
                ++counts[0], ++counts[1], ++counts[2];
                marked[i] = 1;
                if (shadowRay(surface.position + surface.normal * rayOffset_, in.toLight, in.distance, &packet[n]))
                    pixel[n++] = i;
                else
                    mask[i] = 1.0f;
            }
        }
        casters_.rays.anyHits(std::span<const Ray>(packet, n), std::span<uint8_t>(occludedRays, n));
        for (size_t k = 0; k < n; ++k) mask[pixel[k]] = occludedRays[k] ? 0.0f : 1.0f;
    }
    /// 8x8 pixels: a packet of kMaxGridPacketRays, the paper's best size (§4.1).
    static constexpr int kPacketTilePixels = 8;
    static_assert(kPacketTilePixels * kPacketTilePixels <= kMaxGridPacketRays && kMaxGridPacketRays <= kMaxWidePacketRays);

private:
    /// A receiver in map space: its continuous texel position and the plane through it, as depth
    /// change per texel step along x and y.
    struct Receiver {
        float qx, qy, depth;
        float slopeX, slopeY;
        float texelWorld;
        float bias;
    };

    Receiver receiver(const glm::vec3& p, const glm::vec3& n, const ShadowMapTexel& t) const {
        const ShadowMapFace& face = map_.face(t.face);
        const glm::vec3 q(t.position, t.receiverDepth);  // where locate found the point
        const glm::vec3 nv = glm::mat3(face.viewFromWorld) * n;
        // The receiver's plane, carried one texel over: view x is texel x, view y is texel -y. Its
        // depth changes by the normal's sideways component times the texel's width, over how
        // squarely it faces the light's ray: for an orthographic face that ray is the view axis
        // (nv.z); for a perspective one it is the ray through the receiver, n . (light - p) /
        // depth, which is nv.z on the axis only (off it, near a spot light's cone edge, nv.z
        // alone misjudges a grazing receiver's slope severalfold).
        const float facing = face.perspective ? glm::dot(nv, -glm::vec3(face.viewFromWorld * glm::vec4(p, 1.0f))) / q.z : nv.z;
        const float nz = std::max(facing, 0.05f);  // steeper than 20 texels of depth per texel: clamp
        const float depthPerTexel = t.texelWorld / nz;  // times the normal's x, or -y: the plane's slopes
        Receiver r;
        r.qx = q.x;
        r.qy = q.y;
        r.depth = q.z;
        r.texelWorld = t.texelWorld;
        r.slopeX = nv.x * depthPerTexel;
        r.slopeY = -nv.y * depthPerTexel;
        r.bias = 0.5f * t.texelWorld + rayOffset_;  // rounding of the map and of curved receivers
        return r;
    }

    /// Lit by the map at texel (x + dx, y + dy): its stored depth against the receiver's plane at
    /// that texel's centre (a receiver-plane depth bias, so sloped receivers do not shadow themselves).
    bool litAt(const Receiver& r, const ShadowMapTexel& t, int dx, int dy) const {
        const float cx = float(t.x + dx) + 0.5f - r.qx, cy = float(t.y + dy) + 0.5f - r.qy;
        const float planeDepth = r.depth + r.slopeX * cx + r.slopeY * cy;
        return planeDepth - r.bias <= map_.depthAt(t.face, t.x + dx, t.y + dy);
    }

    bool potentiallyIncorrect(const Receiver& r, const ShadowMapTexel& t, int* decision) const {
        const int size = map_.size();
        if (t.x < 1 || t.y < 1 || t.x >= size - 1 || t.y >= size - 1) return true;  // a neighbour is off the face
        const FaceMarks& marks = faces_[size_t(t.face)];
        // litAt over the 3x3 texels, all inside the face: the same comparison, read straight
        // from the depth rows and counted without a branch (a shadow edge passes near unless all
        // nine agree, which an early exit would mispredict at every edge).
        const float* depth = map_.face(t.face).depth.data();
        int lit = 0;
        for (int dy = -1; dy <= 1; ++dy) {
            const float* row = depth + size_t(t.y + dy) * size_t(size);
            const float cy = float(t.y + dy) + 0.5f - r.qy;
            for (int dx = -1; dx <= 1; ++dx) {
                const float cx = float(t.x + dx) + 0.5f - r.qx;
                const float planeDepth = r.depth + r.slopeX * cx + r.slopeY * cy;
                lit += planeDepth - r.bias <= row[t.x + dx];
            }
        }
        if (lit != 0 && lit != 9) return true;
        const bool centre = lit == 9;
        // A thin caster the map may have missed, tested as the map's own texel would be (litAt):
        // its depth at the texel centre against the receiver's plane carried there. Only the
        // receiver's own texel matters: the ray to the light leaves from its point there, and a
        // caster crossing that ray marked the texel. A finely tessellated surface is thus not
        // its own thin caster, as the nearest vertex of each of its triangles would make it.
        const float planeDepth = r.depth + r.slopeX * (float(t.x) + 0.5f - r.qx) + r.slopeY * (float(t.y) + 0.5f - r.qy);
        if (marks.thinDepth[size_t(t.y) * size + t.x] < planeDepth - r.bias) return true;
        if (options_.soft && nearDiscontinuity(r, t)) return true;
        *decision = centre ? 1 : 0;
        return false;
    }

    // ---- soft shadows: where the penumbra can be -----------------------------------------------

    /// How far sideways, in texels at the blocker, the rays from a receiver to the light's disk
    /// reach at a blocker's depth: the light's radius carried over the gap between them.
    float penumbraReachTexels(const Receiver& r, const ShadowMapTexel& t, float blockerDepth) const {
        const ShadowMapFace& face = map_.face(t.face);
        const float gap = std::max(0.0f, r.depth - blockerDepth);
        if (face.perspective) {
            const float texelAtBlocker = 2.0f * face.halfExtent * std::max(blockerDepth, face.nearPlane) / float(map_.size());
            return options_.lightRadius * gap / std::max(r.depth, 1e-6f) / texelAtBlocker;
        }
        return options_.lightRadius * gap / r.texelWorld;
    }

    /// The widest penumbra a receiver can see (map mode's filter width), in whole texels, from
    /// blockers no nearer the light than the face's nearest caster.
    int penumbraTexels(const Receiver& r, const ShadowMapTexel& t) const {
        const float reach = penumbraReachTexels(r, t, faces_[size_t(t.face)].nearestDepth);
        return int(std::min(std::ceil(reach) + 1.0f, 1e6f));
    }

    /// Whether a depth discontinuity nearer the light than this receiver lies within reach of its
    /// rays to the light's disk at that discontinuity's own depth: only such an edge can cast a
    /// partial shadow on it (a receiver no silhouette reaches sees the whole disk or none of it).
    ///
    /// The search descends the min pyramid of discontinuity depths, from the level whose blocks
    /// are as wide as the widest reach in the face (at most 3 x 3 of them to start). A block can
    /// hold a discontinuity that reaches the receiver only if its nearest depth is nearer than
    /// the receiver and the block's texel centres lie within the reach of that nearest depth (the
    /// widest any of its discontinuities can have), widened by kPenumbraEdgeSlackTexels: the
    /// silhouette itself lies within a texel of the discontinuity texels beside it.
    bool nearDiscontinuity(const Receiver& r, const ShadowMapTexel& t) const {
        const FaceMarks& marks = faces_[size_t(t.face)];
        const float receiverDepth = r.depth - r.bias;
        struct Block {
            int level, x, y;
        };
        // The widest reach any discontinuity in the face can have is the nearest one's. Each block
        // popped pushes at most four, so the stack stays under 9 + 3 levels deep.
        const int levels = int(marks.discontinuityDepth.size());
        const float widest = penumbraReachTexels(r, t, marks.discontinuityDepth.back()[0]) + kPenumbraEdgeSlackTexels;
        const int size = map_.size(), last = size - 1;
        const bool wholeFace = !(widest < float(size));  // NaN too: search from the top
        int start = wholeFace ? levels - 1 : 0;
        while (start + 1 < levels && float(1 << start) < widest) ++start;
        auto texelSpan = [&](float q, int& lo, int& hi) {  // texels whose centres lie within `widest` of q
            lo = wholeFace ? 0 : std::clamp(int(std::ceil(q - widest - 0.5f)), 0, last);
            hi = wholeFace ? last : std::clamp(int(std::floor(q + widest - 0.5f)), 0, last);
        };
        int tx0, tx1, ty0, ty1;
        texelSpan(r.qx, tx0, tx1);
        texelSpan(r.qy, ty0, ty1);
        Block stack[16 + 3 * 32];
        int top = 0;
        for (int by = ty0 >> start; by <= (ty1 >> start); ++by)
            for (int bx = tx0 >> start; bx <= (tx1 >> start); ++bx) stack[top++] = {start, bx, by};
        while (top > 0) {
            const Block b = stack[--top];
            const float nearest = marks.discontinuityDepth[size_t(b.level)][size_t(b.y) * marks.levelSize[size_t(b.level)] + b.x];
            if (!(nearest < receiverDepth)) continue;
            // The block's texel centres, and the receiver's distance to the nearest of them.
            const float lo = 0.5f, side = float(1 << b.level);
            const float x0 = float(b.x) * side + lo, x1 = std::min(float(b.x + 1) * side, float(size)) - lo;
            const float y0 = float(b.y) * side + lo, y1 = std::min(float(b.y + 1) * side, float(size)) - lo;
            const float dx = std::max({x0 - r.qx, r.qx - x1, 0.0f}), dy = std::max({y0 - r.qy, r.qy - y1, 0.0f});
            const float reach = penumbraReachTexels(r, t, nearest) + kPenumbraEdgeSlackTexels;
            if (dx * dx + dy * dy > reach * reach) continue;  // (a NaN reach is opened)
            if (b.level == 0) {
                // The receiver's own 3x3 texels agreed (potentiallyIncorrect): rays that stay
                // among their centres meet what the map shows there. An edge beyond them that rays
                // reach has a discontinuity texel beyond them too, within a texel of it.
                if (std::abs(b.x - t.x) > 1 || std::abs(b.y - t.y) > 1) return true;
                continue;
            }
            const int below = b.level - 1, n = marks.levelSize[size_t(below)];
            for (int j = 0; j < 2; ++j)
                for (int i = 0; i < 2; ++i)
                    if (2 * b.x + i < n && 2 * b.y + j < n) stack[top++] = {below, 2 * b.x + i, 2 * b.y + j};
        }
        return false;
    }

    /// Map mode, soft: the fraction of lit texels over the penumbra's width (PCF).
    float percentageCloser(const Receiver& r, const ShadowMapTexel& t) const {
        const int reach = std::min(penumbraTexels(r, t), 8);
        int lit = 0, total = 0;
        for (int dy = -reach; dy <= reach; ++dy)
            for (int dx = -reach; dx <= reach; ++dx) {
                lit += litAt(r, t, dx, dy);
                ++total;
            }
        return float(lit) / float(total);
    }

    // ---- rays ------------------------------------------------------------------------------

    float trace(const glm::vec3& p, const glm::vec3& n, const Incidence& in, uint64_t* rays) const {
        const glm::vec3 origin = p + n * rayOffset_;
        if (!options_.soft) {
            ++*rays;
            return occluded(origin, in.toLight, in.distance) ? 0.0f : 1.0f;
        }
        glm::vec3 u, v;
        tangentFrame(in.toLight, u, v);
        // Through the grid, one receiver's rays go as a packet; through the wide BVH, one by one:
        // as a packet they were 5% slower (the dragon on its ground, --soft, 1280x720: mask
        // 255 ms one by one, 270 ms as packets), each ray already testing eight boxes at once.
        if (casters_.rays.grid) return traceSoftAsPacket(origin, in, u, v, rays);
        int lit = 0;
        for (const glm::vec2& s : disk_) {
            const auto [direction, distance] = diskTarget(origin, in, u, v, s);
            lit += !occluded(origin, direction, distance);
        }
        *rays += disk_.size();
        return float(lit) / float(disk_.size());
    }

    /// The direction to one sample `s` of the light's disk (frame u, v about the direction to the
    /// light) and how far it is: infinitely far for a directional light.
    std::pair<glm::vec3, float> diskTarget(const glm::vec3& origin, const Incidence& in, const glm::vec3& u, const glm::vec3& v,
                                           const glm::vec2& s) const {
        if (light_.type == raster::LightType::Directional)
            return {glm::normalize(in.toLight + options_.lightRadius * (s.x * u + s.y * v)), std::numeric_limits<float>::infinity()};
        const glm::vec3 target = light_.position + options_.lightRadius * (s.x * u + s.y * v) - origin;
        const float distance = glm::length(target);
        return {target / distance, distance};
    }

    /// Whether a caster lies on the segment from `origin` toward the light. It is traced from the
    /// light's end back to the receiver: traversal enters the nearer box first, so an occluder is
    /// met before the dense surface about the receiver, every triangle of which a ray leaving the
    /// receiver must first prove it misses. (A lit segment visits the same boxes either way.)
    bool occluded(const glm::vec3& origin, const glm::vec3& direction, float distance) const {
        Ray ray;
        return shadowRay(origin, direction, distance, &ray) && casters_.rays.anyHit(ray);
    }

    /// The ray occluded() asks about, or false where there is none to ask (the segment leaves the
    /// casters' bounds at once).
    bool shadowRay(const glm::vec3& origin, const glm::vec3& direction, float distance, Ray* ray) const {
        const float length = std::isinf(distance) ? exitDistance(origin, direction) : distance * (1.0f - 1e-4f);
        if (!(length > 0.0f)) return false;
        *ray = Ray{origin + direction * length, -direction, 0.0f, length};
        return true;
    }

    /// trace()'s soft shadows through the grid: one receiver's rays toward the light's disk, which
    /// leave nearly together, as one packet (Wald et al.'s soft-shadow packets). Each ray's answer
    /// is its single query's.
    float traceSoftAsPacket(const glm::vec3& origin, const Incidence& in, const glm::vec3& u, const glm::vec3& v,
                            uint64_t* rays) const {
        Ray packet[kMaxGridPacketRays];
        uint8_t occludedRays[kMaxGridPacketRays];
        int lit = 0;
        for (size_t first = 0; first < disk_.size(); first += kMaxGridPacketRays) {
            int n = 0;
            for (size_t k = first; k < std::min(disk_.size(), first + kMaxGridPacketRays); ++k) {
                const auto [direction, distance] = diskTarget(origin, in, u, v, disk_[k]);
                if (shadowRay(origin, direction, distance, &packet[n])) ++n;
                else ++lit;
            }
            casters_.rays.anyHits(std::span<const Ray>(packet, size_t(n)), std::span<uint8_t>(occludedRays, size_t(n)));
            for (int k = 0; k < n; ++k) lit += !occludedRays[k];
        }
        *rays += disk_.size();
        return float(lit) / float(disk_.size());
    }

    /// How far a ray from `origin` runs before it leaves the casters' bounds for good (widened by
    /// the ray offset, so no caster on the boundary is cut off); 0 or less if it never meets them.
    float exitDistance(const glm::vec3& origin, const glm::vec3& direction) const {
        float exit = std::numeric_limits<float>::infinity();
        for (int a = 0; a < 3; ++a) {
            const float toFarSide = (direction[a] < 0.0f ? casters_.bounds.lo[a] - rayOffset_ : casters_.bounds.hi[a] + rayOffset_) - origin[a];
            if (direction[a] != 0.0f) exit = std::min(exit, toFarSide / direction[a]);
        }
        return exit;
    }

    // ---- per-face marks for the hybrid method -------------------------------------------------

    void prepareFace(int f) {
        const int size = map_.size();
        FaceMarks& marks = faces_[size_t(f)];
        const bool hybrid = options_.mode == ShadowMode::Hybrid;
        marks.thinDepth.assign(hybrid ? size_t(size) * size : 0, ShadowMap::kEmpty);
        if (hybrid) thinTriangles_ += markThinTriangles(f, marks);
        if (!options_.soft) return;  // the rest serves the penumbra search alone
        const ShadowMapFace& face = map_.face(f);
        const size_t side = size_t(size);
        auto row = [&](int y) { return face.depth.data() + size_t(y) * side; };
        // The nearest caster, per row and then over the rows (a minimum: the same in any order).
        std::vector<float> rowNearest(side);
        raster::parallelFor(side, [&](size_t y) { rowNearest[y] = *std::min_element(row(int(y)), row(int(y)) + side); });
        marks.nearestDepth = *std::min_element(rowNearest.begin(), rowNearest.end());
        if (!hybrid) return;  // the map's own penumbra width (PCF) needs the nearest depth alone
        // A discontinuity: a texel whose 3x3 neighbourhood spans more depth than a surface four
        // texels steep would (or meets an empty texel: a silhouette against nothing), at the depth
        // of its near side, the one that casts. A thin caster counts as one: its penumbra is as
        // wide as any other's. The neighbourhood's range is taken separably, down the three rows
        // and then across three columns (the same minimum and maximum, in loops that vectorise).
        const int levels = pyramidLevels(size);
        marks.discontinuityDepth.resize(size_t(levels));  // each level's storage kept, every entry rewritten
        marks.levelSize.assign(1, size);
        std::vector<float>& level0 = marks.discontinuityDepth[0];
        level0.resize(side * side);
        constexpr size_t kRowsPerTask = 16;  // each task's two column buffers serve its rows
        raster::parallelFor((side + kRowsPerTask - 1) / kRowsPerTask, [&](size_t task) {
            std::vector<float> columnLo(side), columnHi(side);
            for (size_t yy = task * kRowsPerTask; yy < std::min(side, (task + 1) * kRowsPerTask); ++yy) {
                const int y = int(yy);
                const float *above = row(std::max(0, y - 1)), *centre = row(y), *below = row(std::min(size - 1, y + 1));
                for (size_t x = 0; x < side; ++x) {
                    columnLo[x] = std::min({above[x], centre[x], below[x]});
                    columnHi[x] = std::max({above[x], centre[x], below[x]});
                }
                for (int x = 0; x < size; ++x) {
                    const size_t left = size_t(std::max(0, x - 1)), right = size_t(std::min(size - 1, x + 1));
                    const float lo = std::min({columnLo[left], columnLo[size_t(x)], columnLo[right]});
                    const float hi = std::max({columnHi[left], columnHi[size_t(x)], columnHi[right]});
                    const float texel = 2.0f * face.halfExtent * (face.perspective ? std::min(lo, face.farPlane) : 1.0f) / float(size);
                    const bool edge = (hi - lo > 4.0f * texel) || std::isinf(hi) != std::isinf(lo);
                    level0[yy * side + size_t(x)] = std::min(edge ? lo : ShadowMap::kEmpty, marks.thinDepth[yy * side + size_t(x)]);
                }
            }
        });
        for (int level = 1; level < levels; ++level) {  // each level the minimum of the 2x2 below
            const int below = marks.levelSize.back(), n = (below + 1) / 2;
            const std::vector<float>& b = marks.discontinuityDepth[size_t(level) - 1];
            std::vector<float>& up = marks.discontinuityDepth[size_t(level)];
            up.resize(size_t(n) * n);
            raster::parallelFor(size_t(n), [&](size_t uy) {
                const size_t y0 = 2 * uy, y1 = std::min(size_t(below) - 1, y0 + 1);
                for (size_t ux = 0; ux < size_t(n); ++ux) {
                    const size_t x0 = 2 * ux, x1 = std::min(size_t(below) - 1, x0 + 1);
                    up[uy * n + ux] = std::min({b[y0 * below + x0], b[y0 * below + x1], b[y1 * below + x0], b[y1 * below + x1]});
                }
            });
            marks.levelSize.push_back(n);
        }
    }

    /// Triangles thin in light space (an altitude under one texel while longer than one) and in the
    /// world (slivers, wires, poles narrower than a texel) can fall between texel centres and
    /// vanish from the map. Each marks every texel
    /// it touches (conservative rasterization: the texel's centre within half a diagonal of the
    /// triangle), with its depth there (ThinTriangleDepth).
    /// Returns how many triangles it marked.
    size_t markThinTriangles(int f, FaceMarks& marks) const {
        // Finding the thin triangles is a pass over every caster, in parallel over fixed chunks.
        // Each vertex is carried into the map once (about six triangles share one), for both passes.
        const size_t count = casters_.mesh.triangleCount();
        constexpr size_t kChunk = 16384;
        const std::span<const glm::vec3> positions = casters_.mesh.positions;
        std::vector<glm::vec3>& projected = scratch_.projected;
        projected.resize(positions.size());
        raster::parallelFor((positions.size() + kChunk - 1) / kChunk, [&](size_t chunk) {
            for (size_t v = chunk * kChunk; v < std::min(positions.size(), (chunk + 1) * kChunk); ++v)
                projected[v] = map_.project(f, positions[v]);
        });
        const std::vector<uint8_t>& nearSilhouette = positionsNearSilhouette(f, projected);
        const std::vector<uint32_t>* positionId = nearSilhouette.empty() ? nullptr : &casters_.adjacency->positionId;
        auto atSilhouette = [&](size_t t) {
            if (!positionId) return true;  // no adjacency: any thin triangle may be missed
            for (int c = 0; c < 3; ++c)
                if (nearSilhouette[(*positionId)[casters_.mesh.indices[3 * t + c]]]) return true;
            return false;
        };
        // Alpha-tested casters (rt/caster_alpha_test.h) are marked whole, thin or not: their holes
        // are not in the map at a shadow ray's level of detail, so every receiver behind one
        // takes rays. One that reaches behind the face's near plane cannot be carried into the
        // map; it marks the whole face.
        const HitFilter* alpha = casters_.rays.filter;
        const float nearPlane = map_.face(f).nearPlane;
        std::atomic<bool> wholeFace{false};
        std::vector<std::vector<uint32_t>> thin((count + kChunk - 1) / kChunk);
        raster::parallelFor(thin.size(), [&](size_t chunk) {
            for (size_t t = chunk * kChunk; t < std::min(count, (chunk + 1) * kChunk); ++t) {
                if (alpha && alpha->alphaTests(uint32_t(t))) {
                    int inFront = 0;
                    for (int c = 0; c < 3; ++c) inFront += projected[casters_.mesh.indices[3 * t + c]].z > nearPlane;
                    if (inFront == 3) thin[chunk].push_back(uint32_t(t));
                    else if (inFront > 0) wholeFace.store(true, std::memory_order_relaxed);
                    continue;
                }
                if (atSilhouette(t) && isThin(f, t, projected)) thin[chunk].push_back(uint32_t(t));
            }
        });
        if (wholeFace.load()) {
            std::fill(marks.thinDepth.begin(), marks.thinDepth.end(), nearPlane);
            size_t marked = 0;
            for (const auto& chunk : thin) marked += chunk.size();
            return marked + 1;  // and the one that reached behind
        }
        // Marking is a minimum, the same in any order: thin triangles mark in parallel, each
        // texel's nearest depth kept with a compare-and-swap.
        std::vector<uint32_t> all;
        for (const auto& chunk : thin) all.insert(all.end(), chunk.begin(), chunk.end());
        raster::parallelFor((all.size() + 255) / 256, [&](size_t chunk) {
            for (size_t i = chunk * 256; i < std::min(all.size(), (chunk + 1) * 256); ++i) markTexelsOf(f, all[i], projected, marks);
        });
        return all.size();
    }

    /// Per position id, whether the position touches a silhouette of this face (an edge between a
    /// triangle facing the light and one facing away, or edge-on) or an open edge of the mesh.
    /// A thin triangle none of whose corners does lies inside a sheet the light sees whole: the
    /// sheet around it covers every direction from each corner, so the texels about it sample
    /// the sheet, and where those samples disagree the 3x3 test marks the receiver anyway.
    /// Empty without adjacency.
    const std::vector<uint8_t>& positionsNearSilhouette(int f, const std::vector<glm::vec3>& projected) const {
        std::vector<uint8_t>& near = scratch_.nearSilhouette;
        const MeshAdjacency* adjacency = casters_.adjacency;
        if (!adjacency || adjacency->positionId.size() != casters_.mesh.positions.size()) {
            near.clear();
            return near;
        }
        const float nearPlane = map_.face(f).nearPlane;
        const size_t count = casters_.mesh.triangleCount();
        // Facing in the map's own texel space: the sign of the projected area (0: edge-on, or
        // reaching behind the light's view, both treated as a silhouette).
        std::vector<int8_t>& facing = scratch_.facing;
        facing.resize(count);  // every entry is written below
        constexpr size_t kChunk = 16384;
        raster::parallelFor((count + kChunk - 1) / kChunk, [&](size_t chunk) {
            for (size_t t = chunk * kChunk; t < std::min(count, (chunk + 1) * kChunk); ++t) {
                glm::vec3 q[3];
                cornersInMap(t, projected, q);
                const float twiceArea = (q[1].x - q[0].x) * (q[2].y - q[0].y) - (q[1].y - q[0].y) * (q[2].x - q[0].x);
                const bool inView = q[0].z > nearPlane && q[1].z > nearPlane && q[2].z > nearPlane;
                facing[t] = !inView ? 0 : twiceArea > 0.0f ? 1 : twiceArea < 0.0f ? -1 : 0;
            }
        });
        near.assign(adjacency->positionCount, 0);
        for (const uint32_t p : adjacency->openPositions) near[p] = 1;
        const std::vector<MeshAdjacency::SharedEdge>& edges = adjacency->shared;
        raster::parallelFor((edges.size() + kChunk - 1) / kChunk, [&](size_t chunk) {
            for (size_t e = chunk * kChunk; e < std::min(edges.size(), (chunk + 1) * kChunk); ++e) {
                const MeshAdjacency::SharedEdge& edge = edges[e];
                if (facing[edge.first] == facing[edge.second] && facing[edge.first] != 0) continue;
                // Every writer stores the same 1: the result does not depend on their order.
                std::atomic_ref<uint8_t>(near[edge.from]).store(1, std::memory_order_relaxed);
                std::atomic_ref<uint8_t>(near[edge.to]).store(1, std::memory_order_relaxed);
            }
        });
        return near;
    }

    /// The three corners of triangle t as carried into the map (texel x, texel y, linear depth).
    void cornersInMap(size_t t, const std::vector<glm::vec3>& projected, glm::vec3 q[3]) const {
        for (int c = 0; c < 3; ++c) q[c] = projected[casters_.mesh.indices[3 * t + c]];
    }

    bool isThin(int f, size_t t, const std::vector<glm::vec3>& projected) const {
        const int size = map_.size();
        const ShadowMapFace& face = map_.face(f);
        const TriangleMeshView& mesh = casters_.mesh;
        glm::vec3 q[3];
        cornersInMap(t, projected, q);
        for (int c = 0; c < 3; ++c) {
            if (!(q[c].z > face.nearPlane)) return false;  // reaches behind the light's view: not this face's
        }
        const glm::vec2 e0(q[1] - q[0]), e1(q[2] - q[1]), e2(q[0] - q[2]);
        const float longest = std::sqrt(std::max({glm::dot(e0, e0), glm::dot(e1, e1), glm::dot(e2, e2)}));
        const float twiceArea = std::abs(e0.x * e2.y - e0.y * e2.x);
        if (!(longest >= 1.0f) || twiceArea / longest >= 1.0f) return false;  // small or wide: the map sees it
        // Thin in light space only because it is seen edge-on: part of a surface whose
        // neighbours the map does see. Only triangles thin in the world can slip through.
        const glm::vec3 a = mesh.vertex(t, 0), b = mesh.vertex(t, 1), c = mesh.vertex(t, 2);
        const float longestWorld = std::max({glm::distance(a, b), glm::distance(b, c), glm::distance(c, a)});
        const float altitudeWorld = glm::length(glm::cross(b - a, c - a)) / std::max(longestWorld, 1e-30f);
        const float nearestDepth = std::min({q[0].z, q[1].z, q[2].z});
        const float texelWorld = 2.0f * face.halfExtent * (face.perspective ? nearestDepth : 1.0f) / float(size);
        return altitudeWorld < texelWorld;
    }

    /// Conservative rasterization of one thin triangle: every texel whose centre lies within half
    /// a diagonal of it. A long diagonal sliver has a bounding box of texels quadratic in its
    /// length, so each row only visits the x span the triangle can reach there: the triangle
    /// clipped to the row's slab (centre y +- that distance), widened by the same distance.
    void markTexelsOf(int f, size_t t, const std::vector<glm::vec3>& projected, FaceMarks& marks) const {
        constexpr float kReach = 0.7072f;  // half a texel's diagonal, rounded up
        const int size = map_.size();
        glm::vec3 q[3];
        cornersInMap(t, projected, q);
        const float loY = std::min({q[0].y, q[1].y, q[2].y}), hiY = std::max({q[0].y, q[1].y, q[2].y});
        const int y0 = std::max(0, int(std::floor(loY)) - 1), y1 = std::min(size - 1, int(std::floor(hiY)) + 1);
        const ThinTriangleDepth depth(q, map_.face(f).perspective);
        const glm::vec2 a(q[0]), b(q[1]), c(q[2]);
        for (int y = y0; y <= y1; ++y) {
            const float centreY = float(y) + 0.5f;
            float spanLo, spanHi;
            if (!xSpanInSlab(a, b, c, centreY - kReach, centreY + kReach, spanLo, spanHi)) continue;
            const int x0 = std::max(0, int(std::floor(spanLo - kReach - 0.5f)));
            const int x1 = std::min(size - 1, int(std::ceil(spanHi + kReach - 0.5f)));
            for (int x = x0; x <= x1; ++x) {
                if (!withinReachOfTriangle(glm::vec2(float(x) + 0.5f, centreY), a, b, c, kReach * kReach)) continue;
                keepMinimum(marks.thinDepth[size_t(y) * size + x], depth.at(glm::vec2(float(x) + 0.5f, centreY)));
            }
        }
    }

    /// What the map would have stored at a texel had it seen the thin triangle: the depth of the
    /// triangle's plane at the texel's centre, kept within the depths of its vertices (a sliver's
    /// plane, extrapolated half a texel sideways, can swing far). The plane is taken in depth for
    /// orthographic faces and in 1 / depth for perspective ones, the quantity each projection
    /// keeps affine across the map.
    struct ThinTriangleDepth {
        ThinTriangleDepth(const glm::vec3 q[3], bool perspective) : perspective(perspective) {
            nearest = std::min({q[0].z, q[1].z, q[2].z});
            farthest = std::max({q[0].z, q[1].z, q[2].z});
            float w[3];
            for (int i = 0; i < 3; ++i) w[i] = perspective ? 1.0f / q[i].z : q[i].z;
            const glm::vec2 e1(q[1] - q[0]), e2(q[2] - q[0]);
            const float det = e1.x * e2.y - e1.y * e2.x;
            if (!(std::abs(det) > 0.0f)) return;  // no plane: the nearest vertex stands for it
            gradient = glm::vec2((w[1] - w[0]) * e2.y - (w[2] - w[0]) * e1.y, (w[2] - w[0]) * e1.x - (w[1] - w[0]) * e2.x) / det;
            origin = glm::vec2(q[0]);
            w0 = w[0];
            usable = std::isfinite(gradient.x) && std::isfinite(gradient.y);
        }
        float at(const glm::vec2& centre) const {
            if (!usable) return nearest;
            const float w = w0 + glm::dot(gradient, centre - origin);
            const float depth = perspective ? 1.0f / w : w;
            return depth >= nearest && depth <= farthest ? depth : (depth > farthest ? farthest : nearest);  // NaN: nearest
        }
        bool perspective, usable = false;
        float nearest, farthest, w0 = 0.0f;
        glm::vec2 gradient{0.0f}, origin{0.0f};
    };

    /// The x extent of a triangle's part inside the slab lo <= y <= hi: its vertices in the slab
    /// and its edges' crossings of the slab's two lines. False where it misses the slab.
    static bool xSpanInSlab(const glm::vec2& a, const glm::vec2& b, const glm::vec2& c, float lo, float hi,
                            float& spanLo, float& spanHi) {
        spanLo = std::numeric_limits<float>::infinity();
        spanHi = -spanLo;
        auto take = [&](float x) { spanLo = std::min(spanLo, x), spanHi = std::max(spanHi, x); };
        const glm::vec2* v[3] = {&a, &b, &c};
        for (int i = 0; i < 3; ++i) {
            const glm::vec2 &p = *v[i], &r = *v[(i + 1) % 3];
            if (p.y >= lo && p.y <= hi) take(p.x);
            for (const float line : {lo, hi})
                if ((p.y < line) != (r.y < line)) take(p.x + (r.x - p.x) * ((line - p.y) / (r.y - p.y)));
        }
        return spanLo <= spanHi;
    }

    const raster::Light& light_;
    const ShadowCasters& casters_;
    const ShadowOptions& options_;
    raster::Pipeline& gpu_;
    float rayOffset_ = 0.0f;
    std::vector<glm::vec2> disk_;
    ShadowMap& map_;
    std::vector<FaceMarks>& faces_;
    ThinMarkingScratch& scratch_;
    std::optional<ShadowOptions>& marksOptions_;  // LightShadowStorage::marksOptions
    uint64_t thinTriangles_ = 0;

public:
    uint64_t thinTriangles() const { return thinTriangles_; }
};

}  // namespace

std::vector<glm::vec2> diskSamples(int n) {
    std::vector<glm::vec2> samples;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const float a = 2.0f * (float(i) + 0.5f) / float(n) - 1.0f, b = 2.0f * (float(j) + 0.5f) / float(n) - 1.0f;
            float r, phi;
            if (a == 0.0f && b == 0.0f) {  // the centre (odd N): the angle is undefined
                samples.push_back({0.0f, 0.0f});
                continue;
            }
            if (std::abs(a) > std::abs(b)) {
                r = a;
                phi = 0.78539816f * (b / a);
            } else {
                r = b;
                phi = 1.57079633f - 0.78539816f * (a / b);
            }
            samples.push_back({r * std::cos(phi), r * std::sin(phi)});
        }
    return samples;
}

uint64_t nextCastersVersion() {
    static std::atomic<uint64_t> next{1};
    return next.fetch_add(1, std::memory_order_relaxed);
}

float surfaceRayOffset(const Aabb& casterBounds) {
    const float radius = 0.5f * glm::length(casterBounds.extent());
    return kSurfaceRayOffsetOfRadius * std::max(radius, 1e-3f);
}

bool castsShadows(const raster::Light& light) {
    return light.intensity.x > 0.0f || light.intensity.y > 0.0f || light.intensity.z > 0.0f;
}

ShadowMasks computeShadows(const ScreenSurfaces& surfaces, const raster::Lighting& lighting,
                           const ShadowCasters& casters, const ShadowOptions& options, raster::Pipeline& gpu) {
    ShadowMasks out;
    computeShadows(surfaces, lighting, casters, options, gpu, out);
    return out;
}

namespace {

/// What one light asks of this frame, for Auto's cost model: a map that depends on no camera (a
/// point or spot light's, or a sun's over the whole scene) serves the command's still frames.
ShadowWorkload workload(const raster::Light& light, const ShadowOptions& options, const ShadowCasters& casters,
                        uint64_t coveredPixels) {
    ShadowWorkload w;
    w.receivers = coveredPixels;
    w.soft = options.soft;
    w.raysPerReceiver = options.soft ? std::max(1, options.softSamplesPerSide) * std::max(1, options.softSamplesPerSide) : 1;
    w.casterTriangles = casters.mesh.triangleCount();
    const uint64_t faces = light.type == raster::LightType::Point ? 6 : 1;
    w.mapTexels = faces * uint64_t(options.mapSizeTexels) * uint64_t(options.mapSizeTexels);
    const bool cameraFree = light.type != raster::LightType::Directional || options.focus == MapFocus::Scene;
    w.framesSharingMap = cameraFree ? std::max(1, options.sequenceFrames) : 1;
    return w;
}

/// The mode a light's shadows are drawn in: Auto's choice (recorded in `stats`), else the one
/// asked for. `covered` counts the pixels with a surface once, for every light of the frame.
ShadowMode modeForLight(const raster::Light& light, const ShadowOptions& options, const ShadowCasters& casters,
                        const ScreenSurfaces& surfaces, uint64_t& covered, ShadowStats& stats) {
    if (options.mode != ShadowMode::Auto) return options.mode;
    if (covered == 0)
        covered = uint64_t(std::count_if(surfaces.triangle.begin(), surfaces.triangle.end(),
                                         [](uint32_t t) { return t != ScreenSurfaces::kNone; }));
    const ShadowModeChoice choice = chooseShadowMode(workload(light, options, casters, covered));
    ++(choice.mode == ShadowMode::Hybrid ? stats.autoHybrid : stats.autoRayTraced);
    stats.predictedHybridMs += choice.predictedHybridMs;
    stats.predictedRayTracedMs += choice.predictedRayTracedMs;
    return choice.mode;
}

}  // namespace

void computeShadows(const ScreenSurfaces& surfaces, const raster::Lighting& lighting, const ShadowCasters& casters,
                    const ShadowOptions& options, raster::Pipeline& gpu, ShadowMasks& out) {
    out.width = surfaces.width;
    out.height = surfaces.height;
    out.stats = {};
    out.marked.clear();
    out.visibility.resize(size_t(lighting.lightCount));
    for (std::vector<float>& mask : out.visibility) mask.clear();  // unshadowed until computed (storage kept)
    if (options.mode == ShadowMode::None || casters.mesh.triangleCount() == 0) return;
    const size_t pixels = size_t(surfaces.width) * surfaces.height;
    out.marked.assign(pixels, 0);
    if (out.storage.size() < size_t(lighting.lightCount)) out.storage.resize(size_t(lighting.lightCount));
    uint64_t covered = 0;  // Auto: pixels with a surface, counted once for every light
    const MeshAdjacency* adjacency = casters.adjacency;  // Auto: found for the first light given hybrid
    for (int l = 0; l < lighting.lightCount; ++l) {
        const raster::Light& light = lighting.lights[l];
        if (!castsShadows(light)) continue;
        ++out.stats.lightsShadowed;
        if (!out.storage[size_t(l)]) out.storage[size_t(l)].reset(new LightShadowStorage);
        LightShadowStorage& storage = *out.storage[size_t(l)];
        ShadowOptions lightOptions = options;
        lightOptions.mode = modeForLight(light, options, casters, surfaces, covered, out.stats);
        if (lightOptions.mode == ShadowMode::Hybrid && !adjacency && casters.adjacencyOnDemand) adjacency = casters.adjacencyOnDemand();
        ShadowCasters lightCasters = casters;
        lightCasters.adjacency = adjacency;
        LightShadows shadows(light, lightCasters, lightOptions, gpu, storage);
        double t0 = raster::nowMs();
        if (lightOptions.mode != ShadowMode::RayTraced) ++(shadows.prepareMap(surfaces) ? out.stats.mapsDrawn : out.stats.mapsKept);
        out.stats.mapMs += raster::nowMs() - t0;
        out.stats.thinTriangles += shadows.thinTriangles();
        t0 = raster::nowMs();
        std::vector<float>& mask = out.visibility[size_t(l)];
        mask.assign(pixels, 1.0f);
        // Counters per task (a row, or a tile of packets), summed in task order: integers, so the
        // totals are exact anyway.
        std::vector<std::array<uint64_t, 3>> taskCounts;
        const glm::vec3 toSun = -glm::normalize(light.direction);  // used for directional lights only
        if (shadows.tracesTilesAsPackets()) {
            constexpr int kTile = LightShadows::kPacketTilePixels;
            const int tilesX = (surfaces.width + kTile - 1) / kTile, tilesY = (surfaces.height + kTile - 1) / kTile;
            taskCounts.resize(size_t(tilesX) * size_t(tilesY));
            raster::parallelFor(taskCounts.size(), [&](size_t t) {
                shadows.traceTileAsPacket(surfaces, int(t % size_t(tilesX)) * kTile, int(t / size_t(tilesX)) * kTile, toSun, mask,
                                          out.marked, taskCounts[t]);
            });
        } else {
            taskCounts.resize(size_t(surfaces.height));
            raster::parallelFor(size_t(surfaces.height), [&](size_t y) {
                std::array<uint64_t, 3>& c = taskCounts[y];
                surfaces.forEachSurfaceInRow(int(y), [&](int, size_t i, const Surface& surface) {
                    const Incidence in = incidence(light, toSun, surface.position, surface.normal);
                    if (!in.reaches) {
                        mask[i] = 0.0f;  // the shading gives this light nothing here anyway
                        return;
                    }
                    ++c[0];
                    bool marked = false;
                    mask[i] = shadows.visibility(surface.position, surface.normal, in, &marked, &c[2]);
                    if (marked) {
                        ++c[1];
                        out.marked[i] = 1;
                    }
                });
            });
        }
        for (const auto& c : taskCounts) {
            out.stats.receiverPixels += c[0];
            out.stats.markedPixels += c[1];
            out.stats.raysTraced += c[2];
        }
        out.stats.maskMs += raster::nowMs() - t0;
    }
}

}  // namespace cuberille::rt
