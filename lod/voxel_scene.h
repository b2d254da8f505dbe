#pragma once
// A voxel model as a scene for the rasterizer (Chajdas 2015, chapter 4): each frame selects blocks
// (lod/block_selection.h), expands the selected blocks' voxels into camera-facing quads
// (voxel/face_expansion.h) and submits one draw per block, source-triangle blocks first, then
// voxel blocks, each list front to back. Model space is world space.

#include <vector>

#include "lod/block_selection.h"
#include "raster/pipeline.h"
#include "scene/camera.h"
#include "voxel/face_expansion.h"
#include "voxel/voxel_model.h"

namespace cuberille::lod {

/// What a block's faces are coloured by.
enum class BlockColoring {
    Model,       // the voxels' own colours
    Level,       // --view lod: each block in its level's colour
    Visibility,  // --view visibility: drawn green, source triangles yellow, occlusion-culled red
                 // (drawn last, so from the main camera red shows only where culling was wrong);
                 // seen from a debug camera, frustum-culled nodes grey
};

struct VoxelRenderOptions {
    SelectionOptions selection;
    BlockColoring coloring = BlockColoring::Model;
    bool occlusion = true;  // skip blocks hidden last frame; test them with colour writes off
    /// --debug-camera: select (LOD, frustum, occlusion) for `camera` as usual, but draw what it
    /// selected as seen from this one. No visibility tests are drawn (they would answer for the
    /// wrong view); do not call readOcclusion after such a frame.
    const scene::Camera* viewFrom = nullptr;
};

/// A camera beside, behind and above `main`, looking at its target from about three times as far,
/// for --debug-camera.
scene::Camera debugCameraFor(const scene::Camera& main);

struct VoxelFrameStats {
    SelectionStats selection;
    uint64_t voxelBlocksDrawn = 0, triangleBlocksDrawn = 0;
    uint64_t occlusionCulled = 0;    // selected voxel blocks skipped: hidden in the last frame
    uint64_t visibilityTests = 0;    // blocks drawn with colour writes off to test them
    uint64_t voxelsExpanded = 0, facesEmitted = 0, hybridTriangles = 0;
    double selectMs = 0, expandMs = 0;
};

/// The colour of a level in the `lod` view (level 0 first; repeats after 8).
glm::vec3 levelColor(uint32_t level);

class VoxelScene {
public:
    /// Frames the model from the given angles, lit like a mesh file (a key light above the camera).
    VoxelScene(voxel::VoxelModel model, float azimuthDegrees, float elevationDegrees);

    scene::Camera camera;
    raster::Lighting lighting;
    glm::vec4 background{0.05f, 0.06f, 0.08f, 1.0f};

    const voxel::VoxelModel& model() const { return model_; }

    /// Records one frame's draws into the pipeline (between its beginFrame and endFrame). The
    /// expanded geometry lives in this object until the next call.
    VoxelFrameStats draw(raster::Pipeline& pipeline, int width, int height, const VoxelRenderOptions& options);
    /// After the pipeline's endFrame: which drawn and tested blocks had samples pass the depth test,
    /// for the next frame's occlusion culling.
    void readOcclusion(const raster::PipelineStats& stats);

private:
    /// Occlusion culling (Chajdas 2015, section 4.5): the selected blocks that were hidden in the
    /// last frame are not drawn; after everything visible, each is tested by drawing, with colour
    /// and depth writes off, either itself or, when every selected block under its parent was
    /// hidden, the parent once for all of them (a parent's faces bound its children's).
    void planOcclusion(std::vector<uint32_t>& voxelBlocks, VoxelFrameStats& stats);

    enum Visibility : uint8_t { kUnknown = 0, kVisible = 1, kHidden = 2 };
    voxel::VoxelModel model_;
    std::vector<uint32_t> parent_;           // block -> parent block (the root: itself)
    std::vector<uint8_t> visibility_;        // per block, from the last frame
    std::vector<std::vector<uint32_t>> slotCovers_;  // slot -> selected blocks its result speaks for
    std::vector<uint32_t> tests_;            // this frame's visibility-only blocks (slots follow the drawn ones)
    std::vector<voxel::FaceMesh> faces_;
    struct TriangleMesh {
        std::vector<glm::vec3> positions, normals, colors;
    };
    std::vector<TriangleMesh> triangles_;
};

}  // namespace cuberille::lod
