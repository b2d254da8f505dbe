#include "rt/caster_alpha_test.h"

#include <algorithm>

#include "raster/texture.h"

namespace cuberille::rt {

void CasterAlphaFilter::reset(std::span<const CasterRange> ranges, std::span<const uint32_t> indices) {
    ranges_ = ranges;
    indices_ = indices;
    alphaTested_ = anyAlphaTested(ranges);
    entries_.clear();
    if (!alphaTested_) return;
    entries_.assign(indices.size() / 3, HitFilter::kKept);
    for (const CasterRange& r : ranges)
        if (r.alphaTest)
            std::fill_n(entries_.begin() + r.firstTriangle, r.triangleCount, HitFilter::kAlphaTested);
    filter_ = {entries_, &passesFilter, this};
}

bool anyAlphaTested(std::span<const CasterRange> ranges) {
    return std::any_of(ranges.begin(), ranges.end(), [](const CasterRange& r) { return r.alphaTest.has_value(); });
}

raster::DrawState alphaTestedState(const CasterAlphaTest& a) {
    raster::DrawState state;
    state.shading = raster::ShadingModel::Unlit;
    state.constantColor = glm::vec4(1.0f, 1.0f, 1.0f, a.factor);
    state.alphaMode = raster::AlphaMode::Mask;
    state.alphaCutoff = a.cutoff;
    if (!a.texCoords.empty()) state.textures.baseColor = a.alphaOnly;
    return state;
}

bool CasterAlphaFilter::passes(uint32_t triangle, float u, float v) const {
    // The range holding the triangle: the last that starts at or before it.
    const auto after = std::upper_bound(ranges_.begin(), ranges_.end(), triangle,
                                        [](uint32_t t, const CasterRange& r) { return t < r.firstTriangle; });
    const CasterRange& range = *(after - 1);
    const CasterAlphaTest& test = *range.alphaTest;
    uint32_t corner[3];
    for (int k = 0; k < 3; ++k) corner[k] = indices_[3 * size_t(triangle) + k] - range.firstVertex;
    const float w[3] = {1.0f - u - v, u, v};
    // As the shade stage forms it: the factor times each vertex's alpha, interpolated.
    float alpha = test.factor;
    if (!test.vertexAlphas.empty()) {
        alpha = 0.0f;
        for (int k = 0; k < 3; ++k) alpha += w[k] * (test.factor * test.vertexAlphas[corner[k]]);
    }
    if (test.alphaOnly && !test.texCoords.empty()) {
        const glm::vec2 uv = w[0] * test.texCoords[corner[0]] + w[1] * test.texCoords[corner[1]] + w[2] * test.texCoords[corner[2]];
        alpha *= test.alphaOnly.texture->sample(test.alphaOnly.transform.apply(uv), kShadowRayTextureLod).a;
    }
    return alpha >= test.cutoff;
}

}  // namespace cuberille::rt
