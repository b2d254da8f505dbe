#include "lod/voxel_scene.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>

#include "raster/clock.h"
#include "raster/parallel.h"
#include "raster/sample_pattern.h"
#include "scene/mesh.h"
#include "voxel/packing.h"

namespace cuberille::lod {
namespace {

/// The hierarchical-Z bounds of the frame so far, copied for the expansion's threads to read.
void readDepthFootprint(const raster::Framebuffer& fb, voxel::DepthFootprint& out) {
    out.blockSizePixels = raster::kBlockSizePixels;
    out.blocksX = fb.blocksX(), out.blocksY = fb.blocksY();
    out.keySign = raster::depthKeySign(fb.desc().depthConvention);
    out.farthestKey.resize(size_t(out.blocksX) * size_t(out.blocksY));
    for (int by = 0; by < out.blocksY; ++by)
        for (int bx = 0; bx < out.blocksX; ++bx)
            out.farthestKey[size_t(by) * size_t(out.blocksX) + size_t(bx)] = fb.farthestDepthKeyOfBlock(bx, by);
}

/// The frame's sample positions for voxel::SampleFootprint, in pixels from the pixel's top-left
/// corner (raster/sample_pattern.h gives them in 1/16 pixel from its centre).
voxel::SampleFootprint sampleFootprint(const glm::dmat4& clipFromWorld, const raster::FramebufferDesc& frame) {
    voxel::SampleFootprint f;
    f.clipFromModel = clipFromWorld;
    f.widthPixels = frame.widthPixels, f.heightPixels = frame.heightPixels;
    const raster::SamplePattern& pattern = raster::standardSamplePattern(frame.samples);
    for (int i = 0; i < pattern.count; ++i)
        f.samples.push_back({0.5 + pattern.dx[size_t(i)] / 16.0, 0.5 + pattern.dy[size_t(i)] / 16.0});
    return f;
}

}  // namespace

glm::vec3 levelColor(uint32_t level) {
    static const glm::vec3 palette[8] = {{0.9f, 0.2f, 0.2f}, {0.95f, 0.6f, 0.1f}, {0.9f, 0.9f, 0.2f}, {0.3f, 0.85f, 0.3f},
                                         {0.2f, 0.7f, 0.9f}, {0.3f, 0.35f, 0.95f}, {0.7f, 0.3f, 0.9f}, {0.9f, 0.9f, 0.9f}};
    return palette[level % 8];
}

scene::Camera debugCameraFor(const scene::Camera& main) {
    scene::Camera c = main;
    const glm::vec3 back = main.position - main.target;
    const float distance = glm::length(back);
    // From the side (a quarter turn about the up axis), farther and higher: the selection's front
    // and back, and the frustum's edges, all in view.
    const glm::vec3 side = glm::normalize(glm::cross(main.up, back)) * distance;
    c.position = main.target + back * 1.5f + side * 2.5f + main.up * distance * 1.5f;
    c.nearPlane = main.nearPlane;
    c.farPlane = main.farPlane + distance * 6.0f;
    return c;
}

VoxelScene::VoxelScene(voxel::VoxelModel model, float azimuthDegrees, float elevationDegrees)
    : owned_(std::make_unique<ModelBlocks>(std::move(model))), source_(owned_.get()) {
    initialise(azimuthDegrees, elevationDegrees);
}

VoxelScene::VoxelScene(BlockSource& source, float azimuthDegrees, float elevationDegrees) : source_(&source) {
    initialise(azimuthDegrees, elevationDegrees);
}

void VoxelScene::initialise(float azimuthDegrees, float elevationDegrees) {
    const voxel::VoxelModel& model = source_->layout();
    glm::dvec3 lo(1e300), hi(-1e300);
    for (const voxel::VoxelBlock& b : model.blocks) {
        glm::dvec3 blo, bhi;
        blockBounds(model, b, blo, bhi);
        lo = glm::min(lo, blo);
        hi = glm::max(hi, bhi);
    }
    if (model.blocks.empty()) lo = model.grid.origin, hi = model.grid.origin + model.grid.extent;
    boundsMin_ = glm::vec3(lo);
    boundsMax_ = glm::vec3(hi);
    parent_.resize(model.blocks.size());
    for (uint32_t i = 0; i < model.blocks.size(); ++i) parent_[i] = i;
    for (uint32_t i = 0; i < model.blocks.size(); ++i) {
        const voxel::VoxelBlock& b = model.blocks[i];
        for (int k = 0; k < __builtin_popcount(b.childMask); ++k) parent_[b.firstChild + uint32_t(k)] = i;
    }
    visibility_.assign(model.blocks.size(), kUnknown);
    frameFrom(azimuthDegrees, elevationDegrees);
}

void VoxelScene::frameFrom(float azimuthDegrees, float elevationDegrees) {
    camera = scene::frameBounds(boundsMin_, boundsMax_, azimuthDegrees, elevationDegrees);
    const glm::vec3 toCamera = glm::normalize(camera.position - camera.target);
    lighting = raster::Lighting::directional(glm::normalize(toCamera + glm::vec3(0.0f, 0.8f, 0.0f)), glm::vec3(0.85f),
                                             glm::vec3(0.12f));
}

raster::DrawCall voxelFacesDraw(const glm::mat4& clipFromWorld, std::span<const glm::vec3> positions,
                                std::span<const glm::vec3> normals, std::span<const glm::vec3> colors,
                                std::span<const uint32_t> indices, const raster::Lighting& lighting, const glm::vec3& eye) {
    raster::DrawCall d;
    d.space = raster::PositionSpace::Clip;
    d.clipFromObject = clipFromWorld;
    d.positions = positions;
    d.normals = normals;
    d.vertexColors = colors;
    d.indices = indices;
    d.state.shading = raster::ShadingModel::Lambert;
    d.state.cull = raster::CullMode::None;  // faces are chosen by the camera side already
    d.state.lighting = lighting;
    d.state.cameraPosition = eye;
    return d;
}

void VoxelScene::resetOcclusion() { std::fill(visibility_.begin(), visibility_.end(), kUnknown); }

VoxelFrameStats VoxelScene::draw(raster::Pipeline& pipeline, int width, int height, const VoxelRenderOptions& o) {
    VoxelFrameStats stats;
    BlockSource& source = *source_;
    const voxel::VoxelModel& model = source.layout();
    const float aspect = float(width) / float(height);
    const scene::Camera& eye = o.viewFrom ? *o.viewFrom : camera;  // where the frame is seen from
    const glm::mat4 clipFromWorld = eye.clipFromWorld(aspect);
    SelectionOptions so = o.selection;
    so.viewportHeightPixels = height;
    so.verticalFovRadians = glm::radians(camera.verticalFovDegrees);
    so.orthographic = camera.orthographic;
    so.orthographicHalfHeight = camera.orthographicHalfHeight;
    double t0 = raster::nowMs();
    BlockSelection selection =
        selectBlocks(model, glm::dmat4(camera.clipFromWorld(aspect)), glm::dvec3(camera.position), so);
    source.beginFrame();
    missing_.clear();
    // Source triangles not resident yet: the block's voxels show meanwhile.
    std::vector<uint32_t> triangleBlocks;
    for (uint32_t t : selection.triangleBlocks) {
        if (source.acquire(t, BlockParts::kTriangles)) {
            triangleBlocks.push_back(t);
            continue;
        }
        if (!source.failed(t)) missing_.push_back({0, missing_.size(), {t, BlockParts::kTriangles}});
        selection.voxelBlocks.push_back(t);
    }
    slotCovers_.clear();
    tests_.clear();
    if (o.occlusion) planOcclusion(selection.voxelBlocks, stats);
    std::vector<VoxelDraw> draws;
    for (uint32_t b : selection.voxelBlocks) resolve(b, o.refine, draws, slotCovers_, stats);
    // Visibility tests need their block's voxels; a test that cannot be drawn turns back into
    // draws of the blocks it answers for.
    std::vector<VoxelDraw> testDraws;
    std::vector<std::vector<uint32_t>> testCovers;
    for (VisibilityTest& t : tests_) {
        if (source.acquire(t.block, BlockParts::kVoxels)) {
            testDraws.push_back({t.block, false, {}});
            testCovers.push_back(std::move(t.covers));
        } else {
            for (uint32_t b : t.covers) resolve(b, o.refine, draws, slotCovers_, stats);
        }
    }
    slotCovers_.insert(slotCovers_.end(), testCovers.begin(), testCovers.end());
    stats.selectMs = raster::nowMs() - t0;
    stats.selection = selection.stats;

    // Expansion, block by block in parallel; each block's geometry is its own, so the draws (and
    // the image) do not depend on the thread count.
    t0 = raster::nowMs();
    // Drawn blocks first, then the visibility tests (or, seen from a debug camera, none), then in
    // the visibility view the occlusion-culled blocks themselves: all expand the same way.
    enum Role : uint8_t { kDraw, kTest, kShowCulled, kShowOutside };
    std::vector<VoxelDraw> expand = draws;
    std::vector<uint8_t> roles(expand.size(), kDraw);
    if (!o.viewFrom)
        for (const VoxelDraw& t : testDraws) expand.push_back(t), roles.push_back(kTest);
    if (o.coloring == BlockColoring::Visibility) {
        for (size_t slot = draws.size(); slot < slotCovers_.size(); ++slot)
            for (uint32_t hidden : slotCovers_[slot])
                if (source.acquire(hidden, BlockParts::kVoxels))
                    expand.push_back({hidden, false, {}}), roles.push_back(kShowCulled);
        if (o.viewFrom)  // from outside, the frustum-culled nodes too (grey)
            for (uint32_t outside : selection.frustumCulled)
                if (source.acquire(outside, BlockParts::kVoxels))
                    expand.push_back({outside, false, {}}), roles.push_back(kShowOutside);
    }
    // A model without colours of its own (the voxelizer stored white) is drawn in the albedo a mesh
    // file without colours gets (scene::Mesh::color), so a voxel frame matches the source
    // triangles rendered directly: issue 25 measures its quality against them.
    const glm::vec3 uncolouredAlbedo = scene::Mesh{}.color;
    const glm::vec3* modelColor = model.hasColors ? nullptr : &uncolouredAlbedo;
    triangleTints_.resize(o.coloring == BlockColoring::Model && !modelColor ? 0 : triangleBlocks.size());
    for (size_t k = 0; k < triangleTints_.size(); ++k) {
        const glm::vec3 tint = o.coloring == BlockColoring::Model   ? uncolouredAlbedo
                               : o.coloring == BlockColoring::Level ? lodSourceTrianglesColor()
                                                                    : kSourceTrianglesColor;
        triangleTints_[k].assign(source.triangles(triangleBlocks[k]).positions.size(), tint);
    }
    stats.expandMs = raster::nowMs() - t0;

    auto submit = [&](std::span<const glm::vec3> positions, std::span<const glm::vec3> normals,
                      std::span<const glm::vec3> colors, std::span<const uint32_t> indices, int slot, bool testOnly) {
        if (positions.empty()) return;
        raster::DrawCall d = voxelFacesDraw(clipFromWorld, positions, normals, colors, indices, lighting, eye.position);
        d.state.occlusionSlot = slot;
        if (testOnly) {
            d.state.colorWriteMask = 0;
            d.state.depthWrite = false;
            d.state.shading = raster::ShadingModel::ConstantColor;  // nothing is written: no shading
        }
        pipeline.draw(d);
    };
    for (size_t k = 0; k < triangleBlocks.size(); ++k) {
        const TriangleView t = source.triangles(triangleBlocks[k]);
        submit(t.positions, t.normals, triangleTints_.empty() ? t.colors : std::span<const glm::vec3>(triangleTints_[k]),
               t.indices, -1, false);
        stats.hybridTriangles += t.indices.size() / 3;
        ++stats.triangleBlocksDrawn;
    }
    // Expansion and drawing a chunk of blocks at a time: a chunk expands block by block in
    // parallel (each block's geometry is its own, so the draws, and the image, do not depend on
    // the thread count), is drawn, and the pipeline is flushed before the next chunk reuses the
    // scratch. So a frame holds the faces of one chunk, not of every block it draws, whatever
    // the model's size (docs/streaming.md, memory). Where the flushes fall does not change the
    // image (raster/pipeline.h).
    std::optional<voxel::SampleFootprint> footprint;
    if (o.leaveOutFacesBetweenSamples) footprint = sampleFootprint(glm::dmat4(clipFromWorld), pipeline.framebuffer().desc());
    // Blocks go front to back, so each chunk is tested against the depths of those before it; the
    // first against what the frame drew before its voxels (the source-triangle blocks, or the
    // caller's draws).
    const bool testDepth = footprint && o.leaveOutVoxelsBehindDepth;
    auto drawAndReadDepth = [&] {
        pipeline.flushAndTightenHierarchicalDepth();
        readDepthFootprint(pipeline.framebuffer(), depthFootprint_);
    };
    if (testDepth) drawAndReadDepth();
    for (size_t first = 0, count = 0; first < expand.size(); first += count) {
        size_t chunkVoxels = 0;
        for (count = 0; first + count < expand.size() && count < kBlocksPerExpansionChunk &&
                        (count == 0 || chunkVoxels < o.voxelsPerExpansionChunk);
             ++count)
            chunkVoxels += source.voxels(expand[first + count].block).voxels.size();
        if (faces_.size() < count) faces_.resize(count);
        t0 = raster::nowMs();
        raster::parallelFor(count, [&](size_t i) {
            const size_t k = first + i;
            const VoxelDraw& d = expand[k];
            const voxel::BlockVoxels voxels = source.voxels(d.block);
            glm::vec3 tint = levelColor(voxels.level);
            if (o.coloring == BlockColoring::Visibility)
                tint = roles[k] == kShowCulled    ? kOcclusionCulledColor
                       : roles[k] == kShowOutside ? kOutsideFrustumColor
                                                  : kVisibleBlockColor;
            faces_[i].clear();
            voxel::expandVoxelFaces(model, voxels, glm::dvec3(eye.position), faces_[i],
                                    o.coloring == BlockColoring::Model ? modelColor : &tint,
                                    d.standIn ? &d.region : nullptr, footprint ? &*footprint : nullptr,
                                    testDepth ? &depthFootprint_ : nullptr,
                                    o.leaveOutVoxelsBehindTheirBlock && roles[k] != kTest);
        });
        stats.expandMs += raster::nowMs() - t0;
        for (size_t i = 0; i < count; ++i) {
            const size_t k = first + i;
            const voxel::FaceMesh& f = faces_[i];
            const bool shown = roles[k] == kShowCulled || roles[k] == kShowOutside;
            const bool counted = o.occlusion && !o.viewFrom && !shown;
            submit(f.positions, f.normals, f.colors, f.indices, counted ? int(k) : -1, roles[k] == kTest);
            if (shown) continue;
            stats.voxelsExpanded += f.voxels;
            stats.facesEmitted += f.faces;
            stats.facesBetweenSamples += f.facesBetweenSamples;
            stats.facesBehindDepth += f.facesBehindDepth;
            ++(roles[k] == kTest ? stats.visibilityTests : stats.voxelBlocksDrawn);
        }
        if (testDepth && first + count < expand.size())
            drawAndReadDepth();
        else
            pipeline.flush();
        releaseExcessFaceScratch();
    }

    // The worst-served first: a hole, then the coarsest stand-in; among equals, front to back.
    std::stable_sort(missing_.begin(), missing_.end(), [](const MissingBlock& a, const MissingBlock& b) {
        return a.gap != b.gap ? a.gap > b.gap : a.order < b.order;
    });
    std::vector<BlockRequest> requests;
    for (const MissingBlock& m : missing_) requests.push_back(m.request);
    source.endFrame(std::move(requests));
    return stats;
}

void VoxelScene::resolve(uint32_t block, Refinement refine, std::vector<VoxelDraw>& draws,
                         std::vector<std::vector<uint32_t>>& covers, VoxelFrameStats& stats) {
    BlockSource& source = *source_;
    const voxel::VoxelModel& model = source.layout();
    if (source.acquire(block, BlockParts::kVoxels)) {
        draws.push_back({block, false, {}});
        covers.push_back({block});
        return;
    }
    ++stats.missingBlocks;
    const bool failed = source.failed(block);
    const int levels = int(model.blocks.front().level) + 1;
    if (refine == Refinement::Partial && !failed) {
        ++stats.holes;
        missing_.push_back({levels, missing_.size(), {block, BlockParts::kVoxels}});
        return;
    }
    uint32_t ancestor = block;
    do ancestor = parent_[ancestor];
    while (ancestor != 0 && (source.failed(ancestor) || !source.acquire(ancestor, BlockParts::kVoxels)));
    const voxel::VoxelBlock& b = model.blocks[block];
    const voxel::VoxelBlock& a = model.blocks[ancestor];
    if (!failed) missing_.push_back({int(a.level - b.level), missing_.size(), {block, BlockParts::kVoxels}});
    if (ancestor == block || !source.acquire(ancestor, BlockParts::kVoxels)) {  // nothing resident above
        ++stats.holes;
        return;
    }
    // The block's cell in the ancestor's voxels (rounded outwards when it is under one voxel).
    const uint32_t shift = a.level - b.level, size = model.blockSize;
    const glm::uvec3 cellLo = b.coord * size, cellHi = cellLo + size;
    VoxelDraw d{ancestor, true, {}};
    d.region.lo = (cellLo >> shift) - a.coord * size;
    d.region.hi = ((cellHi + ((1u << shift) - 1u)) >> shift) - a.coord * size;
    draws.push_back(d);
    covers.push_back({block});
    ++stats.standIns;
}

// Each scratch slot keeps the capacity of the largest block it expanded; past the cap, all of it
// is freed, so what the scratch holds between chunks and frames stays bounded.
void VoxelScene::releaseExcessFaceScratch() {
    size_t bytes = 0;
    for (const voxel::FaceMesh& f : faces_)
        bytes += (f.positions.capacity() + f.normals.capacity() + f.colors.capacity()) * sizeof(glm::vec3) +
                 f.indices.capacity() * sizeof(uint32_t);
    if (bytes > kFaceScratchBytes) faces_.clear(), faces_.shrink_to_fit();
}

void VoxelScene::planOcclusion(std::vector<uint32_t>& voxelBlocks, VoxelFrameStats& stats) {
    std::vector<uint32_t> drawn;
    std::map<uint32_t, std::vector<uint32_t>> hiddenByParent;  // ordered: the same plan every run
    std::map<uint32_t, int> selectedUnderParent;
    for (uint32_t i : voxelBlocks) ++selectedUnderParent[parent_[i]];
    for (uint32_t i : voxelBlocks) {
        if (visibility_[i] == kHidden) hiddenByParent[parent_[i]].push_back(i);
        else drawn.push_back(i);
    }
    stats.occlusionCulled = voxelBlocks.size() - drawn.size();
    for (auto& [parent, hidden] : hiddenByParent) {
        // Every selected block under the parent was hidden: the parent's faces bound them all.
        if (parent != hidden.front() && int(hidden.size()) == selectedUnderParent[parent]) {
            tests_.push_back({parent, hidden});
            continue;
        }
        for (uint32_t i : hidden) tests_.push_back({i, {i}});
    }
    voxelBlocks = std::move(drawn);
}

void VoxelScene::readOcclusion(const raster::PipelineStats& stats) {
    for (size_t slot = 0; slot < slotCovers_.size(); ++slot) {
        const bool passed = slot < stats.occlusionSamplesPassed.size() && stats.occlusionSamplesPassed[slot] > 0;
        for (uint32_t i : slotCovers_[slot]) visibility_[i] = passed ? kVisible : kHidden;
    }
}

}  // namespace cuberille::lod
