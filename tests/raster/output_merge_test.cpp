// Output merge and its counters: colour write masks (visibility-only draws), per-draw occlusion
// counters, facing culling, and the overdraw record behind `--view overdraw`.

#include <gtest/gtest.h>

#include "raster/pipeline.h"
#include "tests/raster/reference_raster.h"
#include "tests/raster/test_support.h"

namespace cuberille::testing {
namespace {

// Window-space quad as two triangles, at depth z, counter-clockwise on screen (front-facing).
void addQuad(std::vector<glm::vec3>& p, float x0, float y0, float x1, float y1, float z) {
    p.insert(p.end(), {{x0, y0, z}, {x0, y1, z}, {x1, y1, z}, {x0, y0, z}, {x1, y1, z}, {x1, y0, z}});
}

// One frame holding one draw.
void renderOne(raster::Pipeline& p, const raster::FramebufferDesc& desc, const raster::DrawCall& draw) {
    p.beginFrame(desc);
    p.draw(draw);
    p.endFrame();
}

raster::DrawCall windowDraw(const std::vector<glm::vec3>& positions, glm::vec4 color) {
    raster::DrawCall d;
    d.space = raster::PositionSpace::Window;
    d.positions = positions;
    d.state.constantColor = color;
    return d;
}

TEST(ColorWriteMask, VisibilityOnlyDrawWritesDepthButNoColor) {
    std::vector<glm::vec3> front, back;
    addQuad(front, 4, 4, 20, 20, 0.2f);
    addQuad(back, 0, 0, 32, 32, 0.5f);
    raster::Pipeline p;
    p.beginFrame(frame(32, 32, 4));
    raster::DrawCall occluder = windowDraw(front, glm::vec4(1, 0, 0, 1));
    occluder.state.colorWriteMask = 0;  // depth only
    p.draw(occluder);
    p.draw(windowDraw(back, glm::vec4(0, 1, 0, 1)));
    p.endFrame();
    EXPECT_EQ(sampleColor(p.framebuffer(), 10, 10, 0), glm::vec4(0, 0, 0, 0)) << "hidden, no colour";
    EXPECT_EQ(sampleColor(p.framebuffer(), 25, 25, 0), glm::vec4(0, 1, 0, 1));
}

TEST(ColorWriteMask, WritesOnlyTheMaskedChannels) {
    std::vector<glm::vec3> quad;
    addQuad(quad, 0, 0, 8, 8, 0.5f);
    raster::FramebufferDesc d = frame(8, 8, 1);
    d.clearColor = {0.25f, 0.25f, 0.25f, 0.25f};
    raster::DrawCall draw = windowDraw(quad, glm::vec4(1.0f));
    draw.state.colorWriteMask = raster::kWriteGreen | raster::kWriteAlpha;
    raster::Pipeline p;
    renderOne(p, d, draw);
    EXPECT_EQ(sampleColor(p.framebuffer(), 3, 3, 0), glm::vec4(0.25f, 1.0f, 0.25f, 1.0f));
}

TEST(OcclusionQuery, CountsSamplesThatPassedDepthPerSlot) {
    std::vector<glm::vec3> occluder, hidden, partly;
    addQuad(occluder, 0, 0, 16, 32, 0.1f);
    addQuad(hidden, 2, 2, 10, 10, 0.5f);    // entirely behind the occluder
    addQuad(partly, 8, 0, 24, 32, 0.5f);    // half behind it
    raster::Pipeline p;
    p.beginFrame(frame(32, 32, 4));
    p.draw(windowDraw(occluder, glm::vec4(1)));
    raster::DrawCall a = windowDraw(hidden, glm::vec4(1));
    a.state.occlusionSlot = 0;
    a.state.colorWriteMask = 0;
    p.draw(a);
    raster::DrawCall b = windowDraw(partly, glm::vec4(1));
    b.state.occlusionSlot = 2;
    p.draw(b);
    p.endFrame();
    const auto& q = p.stats().occlusionSamplesPassed;
    ASSERT_EQ(q.size(), 3u);
    EXPECT_EQ(q[0], 0u);
    EXPECT_EQ(q[1], 0u);
    EXPECT_EQ(q[2], 8u * 32u * 4u);  // columns 16..23 of 32 rows, 4 samples each
}

TEST(Culling, BackAndFrontFacesFollowScreenWinding) {
    std::vector<glm::vec3> ccw = {{2, 2, 0.5f}, {2, 14, 0.5f}, {14, 14, 0.5f}};  // CCW on screen
    std::vector<glm::vec3> cw = {ccw[0], ccw[2], ccw[1]};
    for (auto [cull, positions, drawn] :
         {std::tuple{raster::CullMode::Back, ccw, true}, std::tuple{raster::CullMode::Back, cw, false},
          std::tuple{raster::CullMode::Front, ccw, false}, std::tuple{raster::CullMode::Front, cw, true},
          std::tuple{raster::CullMode::None, cw, true}}) {
        raster::DrawCall d = windowDraw(positions, glm::vec4(1));
        d.state.cull = cull;
        raster::Pipeline p;
        renderOne(p, frame(16, 16, 1), d);
        EXPECT_EQ(p.stats().counters.trianglesCulled, drawn ? 0u : 1u);
        EXPECT_EQ(p.stats().counters.samplesPassed > 0, drawn);
    }
}

TEST(ShadingModels, UnlitIgnoresTheLightLambertDoesNot) {
    std::vector<glm::vec3> quad;
    addQuad(quad, 0, 0, 8, 8, 0.5f);
    const std::vector<glm::vec3> normals(6, glm::vec3(0, 0, 1));
    for (auto [model, expected] : {std::pair{raster::ShadingModel::Unlit, 0.6f},
                                   std::pair{raster::ShadingModel::Lambert, 0.6f * 0.25f}}) {
        raster::DrawCall d = windowDraw(quad, glm::vec4(0.6f, 0.6f, 0.6f, 1.0f));
        d.normals = normals;
        d.state.shading = model;
        d.state.lighting = raster::Lighting::directional(glm::vec3(0, 0, 1), glm::vec3(0.0f), glm::vec3(0.25f));  // ambient only
        raster::Pipeline p;
        renderOne(p, frame(8, 8, 1), d);
        EXPECT_FLOAT_EQ(sampleColor(p.framebuffer(), 4, 4, 0).r, expected);
    }
}

TEST(AlphaModes, MaskDiscardsBelowTheCutoffWithoutWritingDepth) {
    std::vector<glm::vec3> front, back;
    addQuad(front, 0, 0, 8, 8, 0.2f);
    addQuad(back, 0, 0, 8, 8, 0.6f);
    for (auto [alpha, frontVisible] : {std::pair{0.4f, false}, std::pair{0.6f, true}}) {
        raster::Pipeline p;
        p.beginFrame(frame(8, 8, 4));
        raster::DrawCall d = windowDraw(front, glm::vec4(1, 0, 0, alpha));
        d.state.shading = raster::ShadingModel::Unlit;
        d.state.alphaMode = raster::AlphaMode::Mask;
        d.state.alphaCutoff = 0.5f;
        p.draw(d);
        raster::DrawCall behind = windowDraw(back, glm::vec4(0, 1, 0, 1));
        behind.state.occlusionSlot = 0;
        p.draw(behind);
        p.endFrame();
        // A discarded front quad leaves no depth behind: the back quad then passes everywhere.
        // A surviving masked sample writes alpha 1: the alpha channel holds coverage.
        EXPECT_EQ(sampleColor(p.framebuffer(), 4, 4, 0), frontVisible ? glm::vec4(1, 0, 0, 1) : glm::vec4(0, 1, 0, 1));
        EXPECT_EQ(p.stats().occlusionSamplesPassed[0], frontVisible ? 0u : 8u * 8u * 4u);
    }
}

// glTF's OPAQUE ignores the colour's alpha: a surface drawn opaque writes alpha 1 whatever its
// material's alpha, in every shading model, so a transparent background resolves to coverage.
// A flat colour (ConstantColor: .tri scenes, visibility buffers) is written as given.
TEST(AlphaModes, OpaqueSurfacesWriteCoverageAsAlpha) {
    std::vector<glm::vec3> quad;
    addQuad(quad, 0, 0, 8, 8, 0.5f);
    for (const raster::ShadingModel model : {raster::ShadingModel::Unlit, raster::ShadingModel::Lambert,
                                             raster::ShadingModel::MetallicRoughness, raster::ShadingModel::ConstantColor}) {
        raster::Pipeline p;
        raster::FramebufferDesc desc = frame(8, 8, 4);
        desc.clearColor = glm::vec4(0.0f);
        p.beginFrame(desc);
        raster::DrawCall d = windowDraw(quad, glm::vec4(1, 0, 0, 0.3f));
        d.state.shading = model;
        p.draw(d);
        p.endFrame();
        const float expected = model == raster::ShadingModel::ConstantColor ? 0.3f : 1.0f;
        for (int s = 0; s < 4; ++s) EXPECT_EQ(sampleColor(p.framebuffer(), 4, 4, s).a, expected) << int(model);
    }
}

TEST(AlphaModes, BlendIsOverCompositing) {
    std::vector<glm::vec3> quad;
    addQuad(quad, 0, 0, 8, 8, 0.5f);
    raster::FramebufferDesc desc = frame(8, 8, 1);
    desc.clearColor = {0, 1, 0, 1};
    raster::DrawCall d = windowDraw(quad, glm::vec4(1, 0, 0, 0.25f));
    d.state.shading = raster::ShadingModel::Unlit;
    d.state.alphaMode = raster::AlphaMode::Blend;
    raster::Pipeline p;
    renderOne(p, desc, d);
    EXPECT_EQ(sampleColor(p.framebuffer(), 3, 3, 0), glm::vec4(0.25f, 0.75f, 0.0f, 1.0f));
}

TEST(Overdraw, RecordsDepthPassingSamplesPerPixel) {
    std::vector<glm::vec3> quads;
    addQuad(quads, 0, 0, 8, 8, 0.9f);
    addQuad(quads, 0, 0, 4, 8, 0.5f);  // in front: passes again on the left half
    addQuad(quads, 4, 0, 8, 8, 0.95f); // behind: fails on the right half
    raster::FramebufferDesc d = frame(8, 8, 2);
    d.recordOverdraw = true;
    raster::Pipeline p;
    renderOne(p, d, windowDraw(quads, glm::vec4(1)));
    const auto& counts = p.framebuffer().overdrawCounts();
    EXPECT_EQ(counts[2 * 8 + 1], 4u);  // left: two layers x 2 samples
    EXPECT_EQ(counts[2 * 8 + 6], 2u);  // right: one layer
}

}  // namespace
}  // namespace cuberille::testing
