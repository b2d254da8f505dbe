#include "lod/voxel_scene.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "raster/clock.h"
#include "raster/parallel.h"
#include "voxel/packing.h"

namespace cuberille::lod {

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

VoxelScene::VoxelScene(voxel::VoxelModel model, float azimuthDegrees, float elevationDegrees) : model_(std::move(model)) {
    glm::dvec3 lo(1e300), hi(-1e300);
    for (const voxel::VoxelBlock& b : model_.blocks) {
        glm::dvec3 blo, bhi;
        blockBounds(model_, b, blo, bhi);
        lo = glm::min(lo, blo);
        hi = glm::max(hi, bhi);
    }
    if (model_.blocks.empty()) lo = model_.grid.origin, hi = model_.grid.origin + model_.grid.extent;
    camera = scene::frameBounds(glm::vec3(lo), glm::vec3(hi), azimuthDegrees, elevationDegrees);
    parent_.resize(model_.blocks.size());
    for (uint32_t i = 0; i < model_.blocks.size(); ++i) parent_[i] = i;
    for (uint32_t i = 0; i < model_.blocks.size(); ++i) {
        const voxel::VoxelBlock& b = model_.blocks[i];
        for (int k = 0; k < __builtin_popcount(b.childMask); ++k) parent_[b.firstChild + uint32_t(k)] = i;
    }
    visibility_.assign(model_.blocks.size(), kUnknown);
    const glm::vec3 toCamera = glm::normalize(camera.position - camera.target);
    lighting = raster::Lighting::directional(glm::normalize(toCamera + glm::vec3(0.0f, 0.8f, 0.0f)), glm::vec3(0.85f),
                                             glm::vec3(0.12f));
}

VoxelFrameStats VoxelScene::draw(raster::Pipeline& pipeline, int width, int height, const VoxelRenderOptions& o) {
    VoxelFrameStats stats;
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
        selectBlocks(model_, glm::dmat4(camera.clipFromWorld(aspect)), glm::dvec3(camera.position), so);
    slotCovers_.clear();
    tests_.clear();
    if (o.occlusion) planOcclusion(selection.voxelBlocks, stats);
    stats.selectMs = raster::nowMs() - t0;
    stats.selection = selection.stats;

    // Expansion, block by block in parallel; each block's geometry is its own, so the draws (and
    // the image) do not depend on the thread count.
    t0 = raster::nowMs();
    // Drawn blocks first, then the visibility tests (or, seen from a debug camera, none), then in
    // the visibility view the occlusion-culled blocks themselves: all expand the same way.
    enum Role : uint8_t { kDraw, kTest, kShowCulled, kShowOutside };
    std::vector<uint32_t> expand = selection.voxelBlocks;
    std::vector<uint8_t> roles(expand.size(), kDraw);
    if (!o.viewFrom)
        for (uint32_t t : tests_) expand.push_back(t), roles.push_back(kTest);
    if (o.coloring == BlockColoring::Visibility) {
        for (size_t slot = selection.voxelBlocks.size(); slot < slotCovers_.size(); ++slot)
            for (uint32_t hidden : slotCovers_[slot]) expand.push_back(hidden), roles.push_back(kShowCulled);
        if (o.viewFrom)  // from outside, the frustum-culled nodes too (grey)
            for (uint32_t outside : selection.frustumCulled) expand.push_back(outside), roles.push_back(kShowOutside);
    }
    faces_.resize(expand.size());
    triangles_.resize(selection.triangleBlocks.size());
    raster::parallelFor(expand.size(), [&](size_t k) {
        const voxel::VoxelBlock& b = model_.blocks[expand[k]];
        glm::vec3 tint = levelColor(b.level);
        if (o.coloring == BlockColoring::Visibility)
            tint = roles[k] == kShowCulled    ? glm::vec3(0.9f, 0.15f, 0.1f)
                   : roles[k] == kShowOutside ? glm::vec3(0.45f)
                                              : glm::vec3(0.2f, 0.8f, 0.3f);
        faces_[k].clear();
        voxel::expandVoxelFaces(model_, b, glm::dvec3(eye.position), faces_[k],
                                o.coloring == BlockColoring::Model ? nullptr : &tint);
    });
    raster::parallelFor(selection.triangleBlocks.size(), [&](size_t k) {
        const voxel::VoxelBlock& b = model_.blocks[selection.triangleBlocks[k]];
        TriangleMesh& m = triangles_[k];
        m.positions.clear(), m.normals.clear(), m.colors.clear();
        const glm::vec3 tint = o.coloring == BlockColoring::Level ? levelColor(0) * 0.6f : glm::vec3(0.95f, 0.85f, 0.2f);
        for (const voxel::SourceTriangle& t : b.triangles)
            for (int v = 0; v < 3; ++v) {
                m.positions.push_back(t.position[v]);
                m.normals.push_back(voxel::unpackNormal1010102(t.normal[v]));
                m.colors.push_back(o.coloring == BlockColoring::Model ? voxel::unpackSrgba8Rgb(t.color[v]) : tint);
            }
    });
    stats.expandMs = raster::nowMs() - t0;

    auto submit = [&](std::span<const glm::vec3> positions, std::span<const glm::vec3> normals,
                      std::span<const glm::vec3> colors, std::span<const uint32_t> indices, int slot, bool testOnly) {
        if (positions.empty()) return;
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
        d.state.cameraPosition = eye.position;
        d.state.occlusionSlot = slot;
        if (testOnly) {
            d.state.colorWriteMask = 0;
            d.state.depthWrite = false;
            d.state.shading = raster::ShadingModel::ConstantColor;  // nothing is written: no shading
        }
        pipeline.draw(d);
    };
    for (const TriangleMesh& m : triangles_) {
        submit(m.positions, m.normals, m.colors, {}, -1, false);
        stats.hybridTriangles += m.positions.size() / 3;
        ++stats.triangleBlocksDrawn;
    }
    for (size_t k = 0; k < faces_.size(); ++k) {
        const voxel::FaceMesh& f = faces_[k];
        const bool shown = roles[k] == kShowCulled || roles[k] == kShowOutside;
        const bool counted = o.occlusion && !o.viewFrom && !shown;
        submit(f.positions, f.normals, f.colors, f.indices, counted ? int(k) : -1, roles[k] == kTest);
        if (shown) continue;
        stats.voxelsExpanded += f.voxels;
        stats.facesEmitted += f.faces;
        ++(roles[k] == kTest ? stats.visibilityTests : stats.voxelBlocksDrawn);
    }
    return stats;
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
    for (uint32_t i : drawn) slotCovers_.push_back({i});
    for (auto& [parent, hidden] : hiddenByParent) {
        // Every selected block under the parent was hidden: the parent's faces bound them all.
        if (parent != hidden.front() && int(hidden.size()) == selectedUnderParent[parent]) {
            tests_.push_back(parent);
            slotCovers_.push_back(hidden);
            continue;
        }
        for (uint32_t i : hidden) {
            tests_.push_back(i);
            slotCovers_.push_back({i});
        }
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
