#pragma once
// Textures: a linear-RGBA float mip chain with glTF's wrap modes and filters.
//
// Filtering follows the texture's sampler (glTF magFilter / minFilter; trilinear by default).
// Conventions: texture coordinates (u, v) in [0, 1] span the image, v down the rows (glTF's);
// texel (i, j) is centred at ((i + 0.5) / width, (j + 0.5) / height). Level of detail is
// log2 of the texels a pixel step covers, from the UV derivatives the shader computes; level 0
// is the full image and each level halves both sides (2x2 box filter, odd sides rounded down,
// at least 1 texel).
// Thread-safety: immutable after construction; sampling is read-only.

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace cuberille::raster {

enum class WrapMode : uint8_t { Repeat, ClampToEdge, MirroredRepeat };

/// glTF's (OpenGL's) minification filters: within a level, and between levels.
enum class MinFilter : uint8_t {
    Nearest,
    Linear,
    NearestMipmapNearest,
    LinearMipmapNearest,
    NearestMipmapLinear,
    LinearMipmapLinear,
};

struct TextureFilter {
    bool magnifyNearest = false;  // magFilter NEAREST; LINEAR otherwise
    MinFilter minify = MinFilter::LinearMipmapLinear;
};

class Texture {
public:
    /// `rgba` is width x height linear RGBA, row-major, top row first.
    Texture(int width, int height, std::vector<glm::vec4> rgba, WrapMode wrapU = WrapMode::Repeat,
            WrapMode wrapV = WrapMode::Repeat, TextureFilter filter = {});

    /// The same texels under other filters (an accuracy knob: `render --texture-filter`).
    void setFilter(TextureFilter filter) { filter_ = filter; }
    TextureFilter filter() const { return filter_; }

    int width(int level = 0) const { return levels_[level].width; }
    int height(int level = 0) const { return levels_[level].height; }
    int levelCount() const { return int(levels_.size()); }
    const glm::vec4& texel(int level, int x, int y) const {
        const Level& l = levels_[level];
        return l.texels[size_t(y) * l.width + x];
    }

    /// With the texture's filters: lod <= 0 magnifies (level 0), lod > 0 minifies. This is
    /// what the shade stage calls.
    glm::vec4 sample(glm::vec2 uv, float lod) const;

    glm::vec4 sampleNearest(int level, glm::vec2 uv) const;
    glm::vec4 sampleBilinear(int level, glm::vec2 uv) const;
    /// lod <= 0 samples level 0; fractional lods blend the two nearest levels.
    glm::vec4 sampleTrilinear(glm::vec2 uv, float lod) const;
    /// Level of detail for UV derivatives per pixel step in x and y.
    float levelOfDetail(glm::vec2 dUVdx, glm::vec2 dUVdy) const;

private:
    struct Level {
        int width, height;
        std::vector<glm::vec4> texels;
    };
    int wrap(int i, int size, WrapMode mode) const;

    std::vector<Level> levels_;
    WrapMode wrapU_, wrapV_;
    TextureFilter filter_;
};

}  // namespace cuberille::raster
