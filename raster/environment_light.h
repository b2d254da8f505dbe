#pragma once
// Image-based lighting: an environment's radiance, prepared once, lighting every lit pixel from
// every direction (the split-sum approximation of Karis, "Real Shading in Unreal Engine 4", 2013,
// as glTF viewers use it).
//
// What the shade stage reads, per pixel, for the metallic-roughness BRDF:
//     occlusion x (c_diff x E(n) + S(r, roughness) x (F0 x A + F90 x B))
// and for Lambert, albedo x occlusion x E(n), where
//   - E(n) is the radiance a white Lambertian surface with normal n shows: (1/pi) times the
//     cosine-weighted integral of the environment, from its projection on the first nine
//     spherical harmonics (Ramamoorthi and Hanrahan, "An Efficient Representation for
//     Irradiance Environment Maps", 2001: the cosine lobe keeps 99% of its energy in them);
//   - S(r, roughness) is the environment around the mirror direction r filtered by the GGX lobe
//     of that roughness, with n = v = r (Karis's assumption), stored for roughness 0, 1/5, ...,
//     1 and interpolated between;
//   - A and B split the BRDF's directional albedo into F0's and F90's parts (the "DFG" table).
// The units are the renderer's (raster/draw.h, Light): a constant environment of radiance c
// makes a white Lambertian surface show c, as an ambient term of c does.
//
// Storage: the filtered levels are octahedral maps (the sphere folded onto a square, +y at its
// centre), each with a one-texel border copied across the fold so bilinear fetches never wrap,
// because the fetch is then a few multiplications and a floor, with no atan2 or acos per pixel:
// vectorisable, and the same bits on every instruction set (the shade stage is compiled per
// set; raster/shade.h).
//
// Everything here is computed per texel from the input alone, in a fixed order: the prepared
// environment is the same bits at any thread count. Immutable once made; shared by frames.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace cuberille::raster {

class EnvironmentLight {
public:
    /// Roughness levels of the specular map: roughness k / (kSpecularLevels - 1).
    static constexpr int kSpecularLevels = 6;
    /// Side of the sharpest level, in texels. An octahedral map of side S spends about
    /// 4 pi / S² steradians a texel; 256 resolves a mirror's reflection about as finely as
    /// a 128-texel cube map face (what glTF viewers prefilter from).
    static constexpr int kSharpestLevelTexels = 256;
    /// The least side of a level. The octahedral fold bends the map along its diagonals, and
    /// bilinear texels bridge the bend with chords; 32 texels a side keep the chords short for a
    /// few kilobytes (levels 3 to 5 all have this side).
    static constexpr int kSmoothestLevelTexels = 32;
    /// The split-sum table's side: (n.v, roughness) on a 32 x 32 grid, bilinear.
    static constexpr int kDfgTableSide = 32;

    /// Prepares an equirectangular radiance map: `width` x `height` linear RGB float triples,
    /// row-major, row 0 at the top (+y, up); column u looks towards
    /// (sin phi, ., -cos phi) with phi = 2 pi (u + 0.5) / width - pi, so the image's centre
    /// column looks down -z (glTF's forward). `intensity` scales the radiance. Non-finite or
    /// negative texels count as 0.
    static EnvironmentLight fromEquirectangular(int width, int height, const float* rgb, float intensity = 1.0f);

    /// The built-in studio: a soft grey dome (brighter above than below) with three soft boxes
    /// (key, fill and rim), as model viewers' neutral environments are lit; see the .cpp.
    static EnvironmentLight neutral(float intensity = 1.0f);

    /// E(n): the radiance a white Lambertian surface of unit normal n shows (the dominant light's
    /// share included).
    glm::vec3 irradiance(const glm::vec3& n) const {
        return irradianceAt(shIrradiance, n.x, n.y, n.z);
    }
    /// S(r, roughness) for a unit direction r and roughness in [0, 1].
    glm::vec3 specular(const glm::vec3& r, float roughness) const {
        glm::vec3 out;
        specularAt(r.x, r.y, r.z, roughness, out.x, out.y, out.z);
        return out;
    }
    /// (A, B) for n.v and roughness in [0, 1].
    static glm::vec2 dfg(float nDotV, float roughness) {
        glm::vec2 ab;
        dfgAt(dfgTable(), nDotV, roughness, ab.x, ab.y);
        return ab;
    }

    // The per-pixel lookups, written for loops across a shade queue (no calls, no branches).

    /// E(n) from the nine coefficients, each already scaled by its band's cosine-lobe factor
    /// and 1/pi, so the sum is the answer.
    static glm::vec3 irradianceAt(const glm::vec3 (&c)[9], float x, float y, float z) {
        return c[0] + c[1] * y + c[2] * z + c[3] * x + c[4] * (x * y) + c[5] * (y * z) + c[6] * (3.0f * z * z - 1.0f) +
               c[7] * (x * z) + c[8] * (x * x - y * y);
    }

    void specularAt(float x, float y, float z, float roughness, float& r, float& g, float& b) const {
        const float level = unitInterval(roughness) * float(kSpecularLevels - 1);
        const int l0 = std::min(int(level), kSpecularLevels - 2);  // level >= 0: truncation is floor
        const float t = level - float(l0);
        // Octahedral coordinates of the direction, in [-1, 1]²; the lower half folded out.
        // A zero direction (a degenerate normal's reflection) reads the map's centre, +y.
        const float inv = 1.0f / std::max(std::fabs(x) + std::fabs(y) + std::fabs(z), 1e-30f);
        float px = x * inv, pz = z * inv;
        const float fx = (1.0f - std::fabs(pz)) * (px < 0.0f ? -1.0f : 1.0f);
        const float fz = (1.0f - std::fabs(px)) * (pz < 0.0f ? -1.0f : 1.0f);
        px = y < 0.0f ? fx : px;
        pz = y < 0.0f ? fz : pz;
        const float u = unitInterval(px * 0.5f + 0.5f), v = unitInterval(pz * 0.5f + 0.5f);
        float r0, g0, b0, r1, g1, b1;
        bilinear(l0, u, v, r0, g0, b0);
        bilinear(l0 + 1, u, v, r1, g1, b1);
        r = r0 + (r1 - r0) * t, g = g0 + (g1 - g0) * t, b = b0 + (b1 - b0) * t;
    }

    /// x clamped to [0, 1], NaN to 0: what indexes a table must never be NaN.
    static float unitInterval(float x) {
        const float low = x > 0.0f ? x : 0.0f;
        return low < 1.0f ? low : 1.0f;
    }

    /// (A, B) at n.v and roughness, bilinear in the table (dfgTable).
    static void dfgAt(const float* table, float nDotV, float roughness, float& a, float& b) {
        constexpr float kLast = float(kDfgTableSide - 1);
        const float fx = unitInterval(nDotV) * kLast, fy = unitInterval(roughness) * kLast;
        const int x0 = std::min(int(fx), kDfgTableSide - 2), y0 = std::min(int(fy), kDfgTableSide - 2);
        const float tx = fx - float(x0), ty = fy - float(y0);
        const int p = 2 * (y0 * kDfgTableSide + x0), q = p + 2 * kDfgTableSide;  // 32-bit: gather lanes
        const float w00 = (1.0f - tx) * (1.0f - ty), w10 = tx * (1.0f - ty), w01 = (1.0f - tx) * ty, w11 = tx * ty;
        a = table[p] * w00 + table[p + 2] * w10 + table[q] * w01 + table[q + 2] * w11;
        b = table[p + 1] * w00 + table[p + 3] * w10 + table[q + 1] * w01 + table[q + 3] * w11;
    }
    /// The split-sum table: kDfgTableSide² (A, B) pairs, row j at roughness j / (side - 1),
    /// column i at n.v = i / (side - 1); computed once per process, in double, in a fixed order.
    static const float* dfgTable();

    /// The nine irradiance coefficients (see irradianceAt).
    glm::vec3 shIrradiance[9] = {};

    /// The environment's dominant light, for a frame that must shadow it (render/: --shadows on a
    /// model lit by the environment alone). A directional light of intensity I from direction d
    /// lights a white Lambertian surface as I max(0, n.d) = I (1/4 + n.d / 2 + 5/16 P2(n.d) - ...)
    /// in Legendre terms; d is the axis of the irradiance's linear band (luminance-weighted) and I
    /// is chosen so the light's n.d / 2 is that band along d. shIrradianceLessDominant is the
    /// irradiance with the light's bands 0 to 2 taken out, so the light and the rest together give
    /// the same diffuse light as the whole environment, up to the clamped cosine's band 4 (3/32 I
    /// at most). The light casts the shadows; the environment's reflections keep it (the light's
    /// own specular is off: Light::specular = 0).
    glm::vec3 dominantDirection{0.0f, 1.0f, 0.0f};  // towards the light
    glm::vec3 dominantIntensity{0.0f};
    glm::vec3 shIrradianceLessDominant[9] = {};
    /// The coefficients a frame shades with: all of shIrradiance, or shIrradianceLessDominant when
    /// the frame draws the dominant light apart (Lighting::environmentLessDominantLight).
    const glm::vec3 (&irradianceHarmonics(bool lessDominantLight) const)[9] {
        return lessDominantLight ? shIrradianceLessDominant : shIrradiance;
    }

    /// Level k's side: halved per level from the sharpest, down to kSmoothestLevelTexels.
    static constexpr int levelSide(int k) { return std::max(kSharpestLevelTexels >> k, kSmoothestLevelTexels); }
    /// Level k's texels: (side + 2)² RGB triples, row-major, the border included.
    const std::vector<float>& levelTexels() const { return texels_; }

private:
    void bilinear(int level, float u, float v, float& r, float& g, float& b) const {
        const int side = levelSide(level);
        const int stride = side + 2;
        // Texel centres at (i + 0.5) / side, shifted by the border: u in [0, 1] gives
        // fx in [0.5, side + 0.5], so (x0, x0 + 1) stays inside the bordered level.
        const float fx = u * float(side) + 0.5f, fy = v * float(side) + 0.5f;
        const int x0 = int(fx), y0 = int(fy);  // fx, fy > 0: truncation is floor
        const float tx = fx - float(x0), ty = fy - float(y0);
        // 32-bit indices (every level together is under 2^18 floats): lanes of gathers.
        const int p = levelOffset_[level] + 3 * (y0 * stride + x0), q = p + 3 * stride;
        const float* t = texels_.data();
        const float w00 = (1.0f - tx) * (1.0f - ty), w10 = tx * (1.0f - ty), w01 = (1.0f - tx) * ty, w11 = tx * ty;
        r = t[p] * w00 + t[p + 3] * w10 + t[q] * w01 + t[q + 3] * w11;
        g = t[p + 1] * w00 + t[p + 4] * w10 + t[q + 1] * w01 + t[q + 4] * w11;
        b = t[p + 2] * w00 + t[p + 5] * w10 + t[q + 2] * w01 + t[q + 5] * w11;
    }

    friend struct EnvironmentPreparation;
    std::vector<float> texels_;              // every level, bordered
    int levelOffset_[kSpecularLevels] = {};  // in floats
};

}  // namespace cuberille::raster
