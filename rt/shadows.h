#pragma once
// The shadow stage: for each shadow-casting light, the fraction of it that reaches the surface
// seen at each pixel, as a screen-space mask the shade stage multiplies in (raster::Light::
// visibility). Four modes trade accuracy for time (Lauterbach section 6.3):
//
//   None       no stage at all.
//   Map        shadow maps alone: one lookup per pixel, wrong near shadow edges and under thin
//              casters, where a map's texels cannot resolve the geometry.
//   Hybrid     the map decides where it is provably right; the rest, the potentially incorrect
//              pixels (PIP), get shadow rays through the BVH. Hard shadows mark a pixel when the
//              map's 3x3 texels around it disagree about it (each compared with the receiver's
//              plane carried to that texel: the receiver-angle test) or when a caster thin in
//              light space lies there (found by marking each thin triangle's texels
//              conservatively). Soft shadows also mark every pixel whose rays to the light's
//              disk reach a depth discontinuity nearer the light (asked of each edge at its own
//              depth), and trace N x N rays there.
//   RayTraced  a shadow ray per pixel (N x N for soft): the reference.
//   Auto       per light and frame, hybrid or ray-traced, whichever a cost model over the
//              frame's counts predicts cheaper (rt/shadow_mode_choice.h); never Map.
//
// Determinism: every pixel's value is a pure function of its surface, the map and the BVH;
// sample positions on area lights are a fixed stratified pattern.

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "raster/draw.h"
#include "raster/pipeline.h"
#include "rt/aabb.h"
#include "rt/caster_rays.h"
#include "rt/deforming_bvh.h"
#include "rt/mesh_adjacency.h"
#include "rt/screen_surfaces.h"
#include "rt/triangle_mesh.h"

namespace cuberille::rt {

enum class ShadowMode : uint8_t { None, Map, Hybrid, RayTraced, Auto };

/// What a directional light's map covers across the light (point and spot lights' maps cover
/// their whole view either way).
///   View   the casters over the receivers this frame sees (a focused map: texels where the
///          camera looks), so a moved camera draws the map again;
///   Scene  every caster, whatever the camera sees: coarser texels, but the map depends on the
///          light and the casters alone, so a turntable or a batch of views keeps it (hybrid
///          traces more of its pixels; its image is the same reference either way).
enum class MapFocus : uint8_t { View, Scene };

struct ShadowOptions {
    ShadowMode mode = ShadowMode::None;
    bool soft = false;
    /// Area lights (--soft): the radius of a disk facing the receiver, in world units for point
    /// and spot lights; for directional lights the tangent of the angular radius (0.0047 is the sun).
    float lightRadius = 0.05f;
    int mapSizeTexels = 2048;
    int softSamplesPerSide = 4;  // N x N rays per pixel that needs them
    MapFocus focus = MapFocus::View;
    /// Frames of the command through which the lights and casters stay still (a turntable's
    /// length; 1 for a single frame or an animation): a map that depends on no camera, drawn
    /// now, serves them all, and Auto spreads its cost over them.
    int sequenceFrames = 1;
};

/// The N x N points on the unit disk soft shadows aim at (Shirley and Chiu's concentric map of an
/// N x N grid of cell centres): fixed, so soft shadows are deterministic.
std::vector<glm::vec2> diskSamples(int samplesPerSide);

struct ShadowStats {
    int lightsShadowed = 0;
    uint64_t receiverPixels = 0;  // pixel-light pairs whose surface faces the light
    uint64_t markedPixels = 0;    // of those, the pairs given rays
    uint64_t raysTraced = 0;
    uint64_t thinTriangles = 0;  // hybrid: caster triangles marked conservatively, over lights and faces
    int mapsDrawn = 0, mapsKept = 0;  // per light with a map: drawn this frame, or kept from the last
    double mapMs = 0.0;   // shadow maps drawn and their hybrid marks (thin casters, discontinuities)
    double maskMs = 0.0;  // every receiver decided: map lookups, marking, rays
    /// Auto: lights given each mode, and the cost model's predictions for the modes it weighed
    /// (summed over lights), to set beside what the chosen one took (mapMs + maskMs).
    int autoHybrid = 0, autoRayTraced = 0;
    double predictedHybridMs = 0.0, predictedRayTracedMs = 0.0;
};

/// One light's shadow maps and hybrid marks, with the scratch space its marking uses (defined in
/// rt/shadows.cpp). Kept from frame to frame in ShadowMasks: a 2048-texel map and its marks are
/// 32 MB, pages a frame would otherwise fault in afresh.
struct LightShadowStorage;
struct LightShadowStorageDelete {
    void operator()(LightShadowStorage* storage) const;
};

struct ShadowMasks {
    int width = 0, height = 0;
    std::vector<std::vector<float>> visibility;  // per light of the Lighting; empty: unshadowed
    std::vector<uint8_t> marked;                 // per pixel: rays were traced for some light
    ShadowStats stats;
    /// Per light: its maps and marks as the last frame into these masks left them, drawn over by
    /// the next one (their contents are not part of the result).
    std::vector<std::unique_ptr<LightShadowStorage, LightShadowStorageDelete>> storage;
};

/// The geometry that casts shadows, in world space, with its BVH (needed by Hybrid and
/// RayTraced only; null for Map).
struct ShadowCasters {
    TriangleMeshView mesh;
    /// What answers the rays (rt/caster_rays.h): the BVH through its own queries, so a lazily
    /// updated one (a deforming mesh, rt/deforming_bvh.h) refreshes the lower boxes they reach,
    /// or a grid built for this pose.
    CasterRays rays;
    Aabb bounds;
    /// The mesh's edge adjacency (Hybrid): thin-caster marking keeps to the triangles at a
    /// silhouette from the light. Null: every thin triangle is marked.
    const MeshAdjacency* adjacency = nullptr;
    /// Names the casters' pose: a light's map (and its hybrid marks) drawn for the same version,
    /// through the same projection, is kept rather than drawn again. A renderer takes a fresh
    /// one (nextCastersVersion) whenever the casters may have moved; 0: never kept.
    uint64_t version = 0;
    /// Auto: finds the adjacency the first time a light is given hybrid (null `adjacency` until
    /// then), so a frame that ray-traces every light never builds it.
    std::function<const MeshAdjacency*()> adjacencyOnDemand;
    /// The casters' draws over `mesh` (rt/caster_alpha_test.h): the maps draw an alpha-tested one
    /// through its alpha test. Empty: one opaque draw. (The rays' alpha test is rays.filter.)
    std::span<const CasterRange> ranges = {};
};

/// A version no casters have had before in this process.
uint64_t nextCastersVersion();

/// `gpu` draws the shadow maps; its render targets are reused from frame to frame.
ShadowMasks computeShadows(const ScreenSurfaces& surfaces, const raster::Lighting& lighting,
                           const ShadowCasters& casters, const ShadowOptions& options, raster::Pipeline& gpu);
/// The same into `out`, whose storage is reused (a renderer keeps one from frame to frame, so a
/// frame's masks cost no fresh pages).
void computeShadows(const ScreenSurfaces& surfaces, const raster::Lighting& lighting, const ShadowCasters& casters,
                    const ShadowOptions& options, raster::Pipeline& gpu, ShadowMasks& out);

/// How far off the surface seen at a pixel its rays start (shadow and occlusion rays), along its
/// normal, as a share of the casters' bounding radius. The surface point is recovered from the
/// visibility buffer in float (rt/screen_surfaces.h: a plane met by the camera ray, a few
/// roundings of coordinates up to the scene's size, so an error of some ulps of the radius); a
/// ray started on the surface could meet its own triangle again. 1e-4 of the radius is far above
/// those ulps (2^-24 each) and below any gap a model's geometry shows at a pixel.
inline constexpr float kSurfaceRayOffsetOfRadius = 1e-4f;
float surfaceRayOffset(const Aabb& casterBounds);

/// Whether a light casts shadows at all in this stage (a light of zero intensity does not).
bool castsShadows(const raster::Light& light);

}  // namespace cuberille::rt
