#pragma once
// A voxel model as a scene for the rasterizer (Chajdas 2015, chapter 4): each frame selects blocks
// (lod/block_selection.h), asks the block source for their data (lod/block_source.h: all in
// memory, or streamed), expands the selected blocks' voxels into camera-facing quads
// (voxel/face_expansion.h) and submits one draw per block, source-triangle blocks first, then
// voxel blocks, each list front to back. Model space is world space.
//
// A selected block whose data is not resident is drawn according to the refinement strategy
// (section 4.6, figures 31 and 32): `Full` lets its nearest resident ancestor stand in, drawing
// only the ancestor's voxels over the missing block's cell, so the model stays closed; `Partial`
// leaves a hole until the block arrives. A block that failed to load always gets its stand-in.

#include <memory>
#include <vector>

#include "lod/block_selection.h"
#include "lod/block_source.h"
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

/// What is drawn for a selected block that is not resident (--refine).
enum class Refinement { Full, Partial };

/// A voxel emits at most three faces of 4 vertices (3 vec3 each) and 6 indices, 168 bytes each,
/// so a chunk's faces take at most 33 MiB (one block past it: a block of 32³ voxels at most).
/// Smaller chunks leave out no more voxels behind the depth drawn
/// (a frame's hidden voxels lie mostly in the blocks of its visible ones) and flush more often:
/// on the 2048³ dragon at pixel error 1, 1280x720, chunks of 65536 voxels and of a single block
/// leave out 95.8k and 96.3k faces, in frames of 139 and 291 ms (`render --stats`).
constexpr size_t kDefaultVoxelsPerExpansionChunk = 65536;

struct VoxelRenderOptions {
    SelectionOptions selection;
    BlockColoring coloring = BlockColoring::Model;
    bool occlusion = true;  // skip blocks hidden last frame; test them with colour writes off
    Refinement refine = Refinement::Full;
    /// --debug-camera: select (LOD, frustum, occlusion) for `camera` as usual, but draw what it
    /// selected as seen from this one. No visibility tests are drawn (they would answer for the
    /// wrong view); do not call readOcclusion after such a frame.
    const scene::Camera* viewFrom = nullptr;
    /// Leave out faces that cover no sample before they become vertices (voxel::SampleFootprint):
    /// the same image; false draws them all, to measure what it saves.
    bool leaveOutFacesBetweenSamples = true;
    /// With it, leave out voxels behind what earlier chunks of the frame drew (voxel::DepthFootprint):
    /// the same image; false draws them, to measure what it saves.
    bool leaveOutVoxelsBehindDepth = true;
    /// With that, also leave out voxels behind nearer voxels of their own block, which the
    /// frame's depth cannot see (a block is drawn in one chunk): the same image, and on the
    /// 2048^3 dragon at pixel error 1 a seventh fewer faces (2.35 -> 2.04 per covered pixel), but
    /// its expansion costs about what the rasterizer saves at one sample and more at four
    /// (docs/performance.md), so it is off unless asked for.
    bool leaveOutVoxelsBehindTheirBlock = false;
    /// Voxels expanded and drawn before each flush, past a chunk's first block (its faces' memory:
    /// at most 504 bytes a voxel). Smaller chunks flush more often and give later chunks more of
    /// the frame's depth to be tested against; the image is the same for any value.
    size_t voxelsPerExpansionChunk = kDefaultVoxelsPerExpansionChunk;
};

/// The draw of voxel faces (expanded quads, model space = world space) as every voxel frame draws
/// them: clip space through the camera, Lambert-lit, both sides (faces already face the camera).
raster::DrawCall voxelFacesDraw(const glm::mat4& clipFromWorld, std::span<const glm::vec3> positions,
                                std::span<const glm::vec3> normals, std::span<const glm::vec3> colors,
                                std::span<const uint32_t> indices, const raster::Lighting& lighting,
                                const glm::vec3& eye);

/// A camera beside, behind and above `main`, looking at its target from about three times as far,
/// for --debug-camera.
scene::Camera debugCameraFor(const scene::Camera& main);

struct VoxelFrameStats {
    SelectionStats selection;
    uint64_t voxelBlocksDrawn = 0, triangleBlocksDrawn = 0;
    uint64_t occlusionCulled = 0;    // selected voxel blocks skipped: hidden in the last frame
    uint64_t visibilityTests = 0;    // blocks drawn with colour writes off to test them
    uint64_t voxelsExpanded = 0, facesEmitted = 0, hybridTriangles = 0;
    uint64_t facesBetweenSamples = 0;  // camera-facing faces left out before drawing: they cover no sample
    uint64_t facesBehindDepth = 0;     // ... left out: their voxel lies behind what the frame drew before
    uint64_t missingBlocks = 0;  // selected but not resident (asked for)
    uint64_t standIns = 0;       // missing blocks an ancestor was drawn for
    uint64_t holes = 0;          // missing blocks nothing was drawn for (partial refinement)
    double selectMs = 0, expandMs = 0;
    /// Pixels the frame covered (raster::coveredPixels, counted after the frame, outside its
    /// time): facesEmitted / coveredPixels is how many faces were drawn for each pixel seen.
    uint64_t coveredPixels = 0;
    double facesPerCoveredPixel() const { return coveredPixels ? double(facesEmitted) / double(coveredPixels) : 0.0; }
};

/// The colour of a level in the `lod` view (level 0 first; repeats after 8).
glm::vec3 levelColor(uint32_t level);

/// The `visibility` view's colours: blocks drawn as voxels, blocks drawn from their source
/// triangles, blocks culled by occlusion (drawn by their visibility test), and, seen from the
/// debug camera, frustum-culled nodes.
inline const glm::vec3 kVisibleBlockColor{0.2f, 0.8f, 0.3f}, kSourceTrianglesColor{0.95f, 0.85f, 0.2f},
    kOcclusionCulledColor{0.9f, 0.15f, 0.1f}, kOutsideFrustumColor{0.45f};
/// The `lod` view's colour of blocks drawn from source triangles (darker than level 0's).
inline glm::vec3 lodSourceTrianglesColor() { return levelColor(0) * 0.6f; }

class VoxelScene {
public:
    /// Frames the model from the given angles, lit like a mesh file (a key light above the camera).
    /// The whole model in memory.
    VoxelScene(voxel::VoxelModel model, float azimuthDegrees, float elevationDegrees);
    /// Blocks from `source`, which must outlive the scene (a streamed model).
    VoxelScene(BlockSource& source, float azimuthDegrees, float elevationDegrees);

    scene::Camera camera;
    raster::Lighting lighting;
    glm::vec4 background{0.05f, 0.06f, 0.08f, 1.0f};

    /// The camera and key light framed again from other angles (as the constructor frames them).
    void frameFrom(float azimuthDegrees, float elevationDegrees);
    /// Forgets what occlusion culling learnt from earlier frames: the next frame tests every block.
    void resetOcclusion();

    /// The model's layout (with its data when it is all in memory).
    const voxel::VoxelModel& model() const { return source_->layout(); }

    /// Records one frame's draws into the pipeline (between its beginFrame and endFrame). The
    /// expanded geometry lives in this object until the next call.
    VoxelFrameStats draw(raster::Pipeline& pipeline, int width, int height, const VoxelRenderOptions& options);
    /// After the pipeline's endFrame: which drawn and tested blocks had samples pass the depth test,
    /// for the next frame's occlusion culling.
    void readOcclusion(const raster::PipelineStats& stats);

private:
    /// A voxel draw: a block's faces, or only those over a missing descendant's cell.
    struct VoxelDraw {
        uint32_t block = 0;
        bool standIn = false;
        voxel::VoxelRegion region;
    };
    /// A selected block as drawn this frame: itself when resident, else per the refinement, its
    /// nearest resident ancestor over its cell (appended to `draws`) or nothing. Missing blocks are
    /// added to `missing` with how badly they are missed (the levels between block and stand-in).
    void resolve(uint32_t block, Refinement refine, std::vector<VoxelDraw>& draws,
                 std::vector<std::vector<uint32_t>>& covers, VoxelFrameStats& stats);
    /// Occlusion culling (Chajdas 2015, section 4.5): the selected blocks that were hidden in the
    /// last frame are not drawn; after everything visible, each is tested by drawing, with colour
    /// and depth writes off, either itself or, when every selected block under its parent was
    /// hidden, the parent once for all of them (a parent's faces bound its children's).
    void planOcclusion(std::vector<uint32_t>& voxelBlocks, VoxelFrameStats& stats);
    /// The visibility tests planned, each a block to draw and the selected blocks it answers for.
    struct VisibilityTest {
        uint32_t block;
        std::vector<uint32_t> covers;
    };

    enum Visibility : uint8_t { kUnknown = 0, kVisible = 1, kHidden = 2 };
    void initialise(float azimuthDegrees, float elevationDegrees);

    glm::vec3 boundsMin_{0.0f}, boundsMax_{0.0f};  // of every block, for the framing

    std::unique_ptr<BlockSource> owned_;  // a model in memory
    BlockSource* source_;
    std::vector<uint32_t> parent_;           // block -> parent block (the root: itself)
    std::vector<uint8_t> visibility_;        // per block, from the last frame
    std::vector<std::vector<uint32_t>> slotCovers_;  // slot -> selected blocks its result speaks for
    std::vector<VisibilityTest> tests_;      // this frame's visibility-only draws (slots follow the drawn ones)
    struct MissingBlock {
        int gap;  // levels between the block and what stands in for it (all levels: nothing does)
        size_t order;
        BlockRequest request;
    };
    std::vector<MissingBlock> missing_;
    /// A chunk of blocks is expanded (in parallel) and drawn before the pipeline is flushed and
    /// the faces' scratch reused: up to this many blocks, enough to keep every core busy, ...
    static constexpr size_t kBlocksPerExpansionChunk = 64;
    /// ... and, past the first block, up to VoxelRenderOptions::voxelsPerExpansionChunk voxels.
    /// Scratch kept from chunk to chunk and frame to frame; past it the slots are freed.
    static constexpr size_t kFaceScratchBytes = size_t(64) << 20;
    void releaseExcessFaceScratch();
    std::vector<voxel::FaceMesh> faces_;  // one chunk's expanded blocks
    voxel::DepthFootprint depthFootprint_;  // what the chunks drawn so far hold, for the next one
    std::vector<std::vector<glm::vec3>> triangleTints_;  // debug views: one colour per vertex
};

}  // namespace cuberille::lod
