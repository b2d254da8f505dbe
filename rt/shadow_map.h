#pragma once
// Shadow maps drawn by the software GPU itself: the casters rendered from the light into a
// depth-only target (no colour storage, colour writes off, both faces, one sample at each texel
// centre). Depths are kept as linear distances along the light's view axis, so bias and
// the hybrid method's tests work in world units for every light type.
//
// Directional lights get one orthographic view fitted to the casters' bounds, narrowed across
// the light to the receivers in view (a focused shadow map: texels spent where the camera looks,
// not over a whole ground plane); spot lights one perspective view spanning the outer cone;
// point lights six 90-degree views (a cube map).

#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "raster/draw.h"
#include "raster/pipeline.h"
#include "rt/aabb.h"
#include "rt/caster_alpha_test.h"
#include "rt/triangle_mesh.h"

namespace cuberille::rt {

struct ShadowMapFace {
    glm::mat4 viewFromWorld{1.0f};
    glm::mat4 clipFromWorld{1.0f};
    /// Rows give texel x and y times w, linear depth and w (1 for orthographic faces): project()
    /// in one product, where every receiver pixel looks its texel up.
    glm::mat4 texelFromWorld{1.0f};
    bool perspective = false;
    float nearPlane = 0.0f, farPlane = 1.0f;
    float halfExtent = 1.0f;  // orthographic: half the side in world units; perspective: tan(half fov)
    std::vector<float> depth;  // size x size, row-major from the top; linear, +inf where empty
};

/// Where a world-space point falls in a shadow map.
struct ShadowMapTexel {
    int face = -1;  // -1: outside every face
    int x = 0, y = 0;
    glm::vec2 position{0.0f};    // continuous, in texels (x, y are its floor)
    float receiverDepth = 0.0f;  // the point's linear depth in that face
    float texelWorld = 0.0f;     // a texel's side in world units at the point's depth
};

class ShadowMap {
public:
    /// Renders the casters' depth from the light with `gpu` (a depth-only target, reused from
    /// frame to frame). `sizeTexels` per side (per face for cube maps). A directional light's map
    /// covers only what `focus` spans across the light, widened by `focusMarginWorld` (the
    /// receivers in view, and how far sideways a soft shadow's rays reach); empty: every caster.
    /// `ranges`: the casters' draws (CasterRange), an alpha-tested one drawn through its alpha
    /// test so its holes let light through; empty: the casters are one opaque draw.
    static ShadowMap render(const raster::Light& light, const TriangleMeshView& casters, const Aabb& casterBounds,
                            int sizeTexels, raster::Pipeline& gpu, std::span<const glm::vec3> focus = {},
                            float focusMarginWorld = 0.0f, std::span<const CasterRange> ranges = {});
    /// The same, drawn into this map: its faces' depth storage is reused (a renderer keeps one
    /// map per light from frame to frame, so a frame's map costs no fresh pages). `castersVersion`
    /// names the casters' current pose (ShadowCasters::version): when it, the size and every
    /// face's projection are what this map was last drawn with, the depth already held is what a
    /// fresh draw would write, and it is kept (returns false); otherwise drawn (returns true).
    /// Version 0 never matches: always drawn.
    bool redraw(const raster::Light& light, const TriangleMeshView& casters, const Aabb& casterBounds, int sizeTexels,
                raster::Pipeline& gpu, std::span<const glm::vec3> focus = {}, float focusMarginWorld = 0.0f,
                uint64_t castersVersion = 0, std::span<const CasterRange> ranges = {});

    ShadowMapTexel locate(const glm::vec3& p) const;
    /// Linear depth at a texel; +inf outside the face or where no caster was drawn.
    float depthAt(int face, int x, int y) const {
        if (x < 0 || y < 0 || x >= size_ || y >= size_) return kEmpty;
        return faces_[size_t(face)].depth[size_t(y) * size_ + x];
    }
    int size() const { return size_; }
    int faceCount() const { return int(faces_.size()); }
    const ShadowMapFace& face(int i) const { return faces_[size_t(i)]; }
    /// Texel position (continuous, in texels) of a point in a face, and its linear depth.
    glm::vec3 project(int face, const glm::vec3& p) const;

    static constexpr float kEmpty = std::numeric_limits<float>::infinity();

private:
    int size_ = 0;
    glm::vec3 lightPosition_{0.0f};  // point lights: the cube's centre
    uint64_t castersVersion_ = 0;     // the casters' pose the depth was drawn from
    std::vector<ShadowMapFace> faces_;
};

}  // namespace cuberille::rt
