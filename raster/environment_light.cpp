#include "raster/environment_light.h"

#include <array>
#include <cmath>
#include <numbers>

#include "raster/parallel.h"

namespace cuberille::raster {

// The preparation, in the order it runs:
//   1. the equirectangular map, cleaned and halved until it is at most kMaxSourceWidth wide;
//   2. its projection on nine spherical harmonics, convolved with the cosine lobe (diffuse);
//   3. an octahedral copy of it, kSourceTexels a side, and that copy's mip chain;
//   4. the specular levels: level 0 the copy at half its side, each rougher level the GGX
//      lobe's filtered importance sampling of the chain (Colbert and Krivanek, GPU Gems 3
//      ch. 20: each sample reads the mip whose texels are the size of the sample's share of
//      the lobe, so a few samples do the work of many without aliasing).
// Each texel is a pure function of the input; rows are shared out to threads, sums that cross
// rows are combined in row order: the same bits at any thread count.

namespace {

constexpr double kPi = std::numbers::pi;

/// Wider maps are box-filtered down first: the lobes read nothing finer than the octahedral
/// copy's texels (about 0.7 degrees), and the irradiance sums nothing finer than its band 2.
constexpr int kMaxSourceWidth = 1024;
/// The octahedral copy's side: twice the sharpest level's, so level 0 is its 2x2 box average.
constexpr int kSourceTexels = 2 * EnvironmentLight::kSharpestLevelTexels;
/// GGX importance samples per texel of each rough level (level 0 is the mirror's, unfiltered).
/// With each sample reading the mip whose texels match its solid angle (and no coarser: the usual
/// +1 mip bias blurred the rough levels 1-2% off), these keep every level within 0.8% of the
/// exact GGX-filtered radiance of a smooth environment (measured 0.74% at most:
/// EnvironmentLight.SpecularLevelsMatchTheGgxFilteredEnvironment; 128 samples everywhere, with
/// the bias, were 8% off at roughness 1); the sharper levels have more texels and narrower lobes,
/// so fewer samples cover them as well.
constexpr int kLobeSamples[EnvironmentLight::kSpecularLevels] = {0, 128, 256, 512, 512, 512};
/// Samples per entry of the split-sum table (computed once, in double).
constexpr int kDfgSamples = 1024;

struct Rgb {
    double r = 0, g = 0, b = 0;
};

/// A float RGB image, row-major.
struct Image {
    int width = 0, height = 0;
    std::vector<float> rgb;
    const float* at(int x, int y) const { return rgb.data() + 3 * (size_t(y) * size_t(width) + size_t(x)); }
    float* at(int x, int y) { return rgb.data() + 3 * (size_t(y) * size_t(width) + size_t(x)); }
};

template <class Body>
void forEachRow(int height, const Body& body) {
    parallelFor(size_t(height), [&](size_t y) { body(int(y)); });
}

/// The point k of n of the Hammersley set: (k / n, radical inverse of k in base 2).
glm::dvec2 hammersley(uint32_t k, uint32_t n) {
    uint32_t bits = k;
    bits = (bits << 16u) | (bits >> 16u);
    bits = ((bits & 0x55555555u) << 1u) | ((bits & 0xAAAAAAAAu) >> 1u);
    bits = ((bits & 0x33333333u) << 2u) | ((bits & 0xCCCCCCCCu) >> 2u);
    bits = ((bits & 0x0F0F0F0Fu) << 4u) | ((bits & 0xF0F0F0F0u) >> 4u);
    bits = ((bits & 0x00FF00FFu) << 8u) | ((bits & 0xFF00FF00u) >> 8u);
    return {double(k) / double(n), double(bits) * 2.3283064365386963e-10};
}

/// A half vector of the GGX lobe of alpha = roughness² around +z, importance-sampled.
glm::dvec3 ggxHalfVector(glm::dvec2 xi, double alpha) {
    const double phi = 2.0 * kPi * xi.x;
    const double cosTheta = std::sqrt((1.0 - xi.y) / (1.0 + (alpha * alpha - 1.0) * xi.y));
    const double sinTheta = std::sqrt(std::max(0.0, 1.0 - cosTheta * cosTheta));
    return {sinTheta * std::cos(phi), sinTheta * std::sin(phi), cosTheta};
}

/// An orthonormal frame (t, b, n) around unit n (Duff et al. 2017, branchless).
void frameAround(const glm::dvec3& n, glm::dvec3& t, glm::dvec3& b) {
    const double sign = n.z >= 0.0 ? 1.0 : -1.0;
    const double a = -1.0 / (sign + n.z), c = n.x * n.y * a;
    t = {1.0 + sign * n.x * n.x * a, sign * c, -sign * n.x};
    b = {c, sign + n.y * n.y * a, -n.y};
}

// --- Directions and the two layouts -------------------------------------------------------

/// The equirectangular map's direction at continuous coordinates (u, v) in [0, 1]².
glm::dvec3 equirectDirection(double u, double v) {
    const double phi = 2.0 * kPi * u - kPi, theta = kPi * v;
    return {std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi)};
}

/// The octahedron's fold of the lower half (y < 0) onto the square's corners; its own inverse.
void foldLowerHalf(double& px, double& pz) {
    const double fx = (1.0 - std::fabs(pz)) * (px < 0.0 ? -1.0 : 1.0);
    const double fz = (1.0 - std::fabs(px)) * (pz < 0.0 ? -1.0 : 1.0);
    px = fx, pz = fz;
}

/// The octahedral map's direction at (u, v) in [0, 1]² (the inverse of specularAt's fold).
glm::dvec3 octahedralDirection(double u, double v) {
    double px = 2.0 * u - 1.0, pz = 2.0 * v - 1.0;
    const double y = 1.0 - std::fabs(px) - std::fabs(pz);
    if (y < 0.0) foldLowerHalf(px, pz);
    return glm::normalize(glm::dvec3(px, y, pz));
}

/// Octahedral (u, v) of a unit direction, as specularAt computes it.
glm::dvec2 octahedralCoordinates(const glm::dvec3& d) {
    const double inv = 1.0 / std::max(std::fabs(d.x) + std::fabs(d.y) + std::fabs(d.z), 1e-300);
    double px = d.x * inv, pz = d.z * inv;
    if (d.y < 0.0) foldLowerHalf(px, pz);
    return {px * 0.5 + 0.5, pz * 0.5 + 0.5};
}

/// Texel (x, y) of a square octahedral level, one step past an edge folded back across it:
/// the octahedron's edges meet their mirror images ((-1, y) is (0, side - 1 - y), and so on).
const float* octahedralTexel(const Image& level, int x, int y) {
    const int side = level.width;
    if (x < 0) x = 0, y = side - 1 - y;
    else if (x >= side) x = side - 1, y = side - 1 - y;
    if (y < 0) y = 0, x = side - 1 - x;
    else if (y >= side) y = side - 1, x = side - 1 - x;
    return level.at(x, y);
}

/// A square octahedral level with the one-texel border of the fold (octahedralTexel) around
/// it, so a bilinear footprint never needs folding: texel (x, y) is stored at (x + 1, y + 1).
struct BorderedLevel {
    int side = 0;
    std::vector<float> rgb;
};

/// A square octahedral level's (side + 2)² texels, its border folded in, written to `out`: the
/// layout of BorderedLevel and of EnvironmentLight's levels alike.
void writeBordered(const Image& level, float* out) {
    const int side = level.width, stride = side + 2;
    for (int y = -1; y <= side; ++y)
        for (int x = -1; x <= side; ++x) {
            const float* t = octahedralTexel(level, x, y);
            float* o = out + 3 * (size_t(y + 1) * stride + size_t(x + 1));
            o[0] = t[0], o[1] = t[1], o[2] = t[2];
        }
}

BorderedLevel bordered(const Image& level) {
    const size_t stride = size_t(level.width) + 2;
    BorderedLevel out{level.width, std::vector<float>(stride * stride * 3)};
    writeBordered(level, out.rgb.data());
    return out;
}

/// Bilinear at (u, v) in [0, 1]², as EnvironmentLight::bilinear reads its levels.
glm::vec3 bilinearOctahedral(const BorderedLevel& level, float u, float v) {
    const int stride = level.side + 2;
    const float fx = u * float(level.side) + 0.5f, fy = v * float(level.side) + 0.5f;
    const int x0 = std::min(int(fx), level.side), y0 = std::min(int(fy), level.side);
    const float tx = fx - float(x0), ty = fy - float(y0);
    const float* p = level.rgb.data() + 3 * (size_t(y0) * stride + size_t(x0));
    const float* q = p + 3 * size_t(stride);
    const float w00 = (1.0f - tx) * (1.0f - ty), w10 = tx * (1.0f - ty), w01 = (1.0f - tx) * ty, w11 = tx * ty;
    return {p[0] * w00 + p[3] * w10 + q[0] * w01 + q[3] * w11, p[1] * w00 + p[4] * w10 + q[1] * w01 + q[4] * w11,
            p[2] * w00 + p[5] * w10 + q[2] * w01 + q[5] * w11};
}

Rgb bilinearEquirect(const Image& map, double u, double v) {
    const double fx = u * map.width - 0.5, fy = std::clamp(v * map.height - 0.5, 0.0, map.height - 1.0);
    const int x0 = int(std::floor(fx)), y0 = std::min(int(fy), map.height - 1);
    const int y1 = std::min(y0 + 1, map.height - 1);
    const double tx = fx - x0, ty = fy - y0;
    auto wrap = [&](int x) { return ((x % map.width) + map.width) % map.width; };
    const float* t00 = map.at(wrap(x0), y0);
    const float* t10 = map.at(wrap(x0 + 1), y0);
    const float* t01 = map.at(wrap(x0), y1);
    const float* t11 = map.at(wrap(x0 + 1), y1);
    auto mix = [&](int c) {
        return (t00[c] * (1 - tx) + t10[c] * tx) * (1 - ty) + (t01[c] * (1 - tx) + t11[c] * tx) * ty;
    };
    return {mix(0), mix(1), mix(2)};
}

// --- 1. The source, cleaned and halved ----------------------------------------------------

/// The 2x2 box average of an image (an odd last row or column averaged with itself): the source's
/// reduction and the octahedral copy's mips alike.
Image halved(const Image& map) {
    Image half{std::max(1, map.width / 2), std::max(1, map.height / 2), {}};
    half.rgb.resize(size_t(half.width) * size_t(half.height) * 3);
    forEachRow(half.height, [&](int y) {
        const int y0 = std::min(2 * y, map.height - 1), y1 = std::min(2 * y + 1, map.height - 1);
        for (int x = 0; x < half.width; ++x) {
            const int x0 = std::min(2 * x, map.width - 1), x1 = std::min(2 * x + 1, map.width - 1);
            for (int c = 0; c < 3; ++c)
                half.at(x, y)[c] = 0.25f * ((map.at(x0, y0)[c] + map.at(x1, y0)[c]) + (map.at(x0, y1)[c] + map.at(x1, y1)[c]));
        }
    });
    return half;
}

Image cleanedSource(int width, int height, const float* rgb, float intensity) {
    Image map{width, height, std::vector<float>(size_t(width) * size_t(height) * 3)};
    for (size_t i = 0; i < map.rgb.size(); ++i) {
        const float x = rgb[i] * intensity;
        map.rgb[i] = std::isfinite(x) && x > 0.0f ? x : 0.0f;
    }
    while (map.width > kMaxSourceWidth) map = halved(map);
    return map;
}

// --- 2. Diffuse: nine coefficients --------------------------------------------------------

/// The nine real spherical harmonics at d, without their normalisation constants, in the order
/// EnvironmentLight::irradianceAt multiplies them.
std::array<double, 9> shPolynomials(const glm::dvec3& d) {
    return {1.0, d.y, d.z, d.x, d.x * d.y, d.y * d.z, 3.0 * d.z * d.z - 1.0, d.x * d.z, d.x * d.x - d.y * d.y};
}

/// Each polynomial's normalisation constant squared (projection multiplies by Y, evaluation
/// by Y again) times its band's cosine-lobe factor A_l / pi (A_0 = pi, A_1 = 2 pi / 3,
/// A_2 = pi / 4), so that the sum of coefficient x polynomial is E(n) / pi.
std::array<double, 9> shScales() {
    const double c0 = 0.28209479177387814, c1 = 0.4886025119029199, c2 = 1.0925484305920792;
    const double c20 = 0.31539156525252005, c22 = 0.5462742152960396;
    const double a0 = 1.0, a1 = 2.0 / 3.0, a2 = 0.25;
    return {c0 * c0 * a0, c1 * c1 * a1, c1 * c1 * a1, c1 * c1 * a1, c2 * c2 * a2, c2 * c2 * a2,
            c20 * c20 * a2, c2 * c2 * a2, c22 * c22 * a2};
}

void projectIrradiance(const Image& map, glm::vec3 (&out)[9]) {
    std::vector<std::array<Rgb, 9>> rows(size_t(map.height));
    forEachRow(map.height, [&](int y) {
        // A texel's exact solid angle: its share of the band between its row's two latitudes.
        const double solidAngle =
            (2.0 * kPi / map.width) * (std::cos(kPi * y / map.height) - std::cos(kPi * (y + 1) / map.height));
        std::array<Rgb, 9>& sums = rows[size_t(y)];
        for (int x = 0; x < map.width; ++x) {
            const std::array<double, 9> p = shPolynomials(equirectDirection((x + 0.5) / map.width, (y + 0.5) / map.height));
            const float* t = map.at(x, y);
            for (int k = 0; k < 9; ++k) {
                const double w = p[size_t(k)] * solidAngle;
                sums[size_t(k)].r += t[0] * w, sums[size_t(k)].g += t[1] * w, sums[size_t(k)].b += t[2] * w;
            }
        }
    });
    const std::array<double, 9> scale = shScales();
    for (int k = 0; k < 9; ++k) {
        Rgb total;
        for (const auto& row : rows) total.r += row[size_t(k)].r, total.g += row[size_t(k)].g, total.b += row[size_t(k)].b;
        const double s = scale[size_t(k)];
        out[k] = glm::vec3(float(total.r * s), float(total.g * s), float(total.b * s));
    }
}

// --- 3. The octahedral copy and its mips --------------------------------------------------

std::vector<Image> octahedralChain(const Image& map) {
    std::vector<Image> chain;
    Image top{kSourceTexels, kSourceTexels, std::vector<float>(size_t(kSourceTexels) * kSourceTexels * 3)};
    forEachRow(kSourceTexels, [&](int y) {
        for (int x = 0; x < kSourceTexels; ++x) {
            Rgb sum;  // 2 x 2 points within the texel
            for (int s = 0; s < 4; ++s) {
                const glm::dvec3 d = octahedralDirection((x + 0.25 + 0.5 * (s & 1)) / kSourceTexels,
                                                         (y + 0.25 + 0.5 * (s >> 1)) / kSourceTexels);
                const double u = (std::atan2(d.x, -d.z) + kPi) / (2.0 * kPi), v = std::acos(std::clamp(d.y, -1.0, 1.0)) / kPi;
                const Rgb t = bilinearEquirect(map, u, v);
                sum.r += t.r, sum.g += t.g, sum.b += t.b;
            }
            float* out = top.at(x, y);
            out[0] = float(sum.r * 0.25), out[1] = float(sum.g * 0.25), out[2] = float(sum.b * 0.25);
        }
    });
    chain.push_back(std::move(top));
    while (chain.back().width > 1) chain.push_back(halved(chain.back()));
    return chain;
}

glm::vec3 trilinearOctahedral(const std::vector<BorderedLevel>& chain, glm::dvec2 uv, double mip) {
    mip = std::clamp(mip, 0.0, double(chain.size() - 1));
    const int m0 = std::min(int(mip), int(chain.size()) - 1), m1 = std::min(m0 + 1, int(chain.size()) - 1);
    const float t = float(mip - m0);
    const float u = float(std::clamp(uv.x, 0.0, 1.0)), v = float(std::clamp(uv.y, 0.0, 1.0));
    const glm::vec3 a = bilinearOctahedral(chain[size_t(m0)], u, v);
    return t == 0.0f ? a : a + (bilinearOctahedral(chain[size_t(m1)], u, v) - a) * t;
}

// --- 4. The specular levels ---------------------------------------------------------------

/// One importance sample of a GGX lobe around +z with n = v: its half vector, n.l, and the mip
/// of the octahedral chain whose texels match the solid angle it stands for. The same for every
/// texel of a level (only the frame turns), so made once per level.
struct LobeSample {
    glm::dvec3 halfVector;
    double nDotL;
    double mip;
};

std::vector<LobeSample> lobeSamples(int level) {
    const int count = kLobeSamples[level];
    const double roughness = double(level) / (EnvironmentLight::kSpecularLevels - 1);
    const double alpha = roughness * roughness, a2 = alpha * alpha;
    const double texelSolidAngle = 4.0 * kPi / (double(kSourceTexels) * kSourceTexels);
    std::vector<LobeSample> samples;
    for (int k = 0; k < count; ++k) {
        const glm::dvec3 h = ggxHalfVector(hammersley(uint32_t(k), uint32_t(count)), alpha);
        const double nDotL = 2.0 * h.z * h.z - 1.0;  // l = 2 (n.h) h - n
        if (nDotL <= 0.0) continue;
        // With n = v, the pdf of l is D(n.h) / 4; a sample stands for 1 / (count x pdf) steradians.
        const double dDenominator = h.z * h.z * (a2 - 1.0) + 1.0;
        const double pdf = a2 / (kPi * dDenominator * dDenominator) / 4.0;
        const double mip = std::max(0.0, 0.5 * std::log2(1.0 / (count * pdf) / texelSolidAngle));
        samples.push_back({h, nDotL, mip});
    }
    return samples;
}

/// The environment filtered by a GGX lobe around n (= v = r): the n.l-weighted mean of the
/// lobe's samples, each read from the chain at its mip (filtered importance sampling).
Rgb filteredRadiance(const std::vector<BorderedLevel>& chain, const glm::dvec3& n, const std::vector<LobeSample>& samples) {
    glm::dvec3 t, b;
    frameAround(n, t, b);
    Rgb sum;
    double weight = 0;
    for (const LobeSample& s : samples) {
        const glm::dvec3 h = t * s.halfVector.x + b * s.halfVector.y + n * s.halfVector.z;
        const glm::dvec3 l = 2.0 * s.halfVector.z * h - n;
        const glm::vec3 radiance = trilinearOctahedral(chain, octahedralCoordinates(l), s.mip);
        sum.r += radiance.r * s.nDotL, sum.g += radiance.g * s.nDotL, sum.b += radiance.b * s.nDotL;
        weight += s.nDotL;
    }
    return {sum.r / weight, sum.g / weight, sum.b / weight};
}

/// Level `level`'s texels, its border included (the fold's copies).
void fillLevel(const std::vector<Image>& chain, const std::vector<BorderedLevel>& borderedChain, int level, float* out) {
    const int side = EnvironmentLight::levelSide(level);
    const std::vector<LobeSample> samples = lobeSamples(level);
    Image inner{side, side, std::vector<float>(size_t(side) * side * 3)};
    forEachRow(side, [&](int y) {
        for (int x = 0; x < side; ++x) {
            float* o = inner.at(x, y);
            if (level == 0) {  // the mirror's level: the copy's next mip, which has this side
                const float* t = chain[1].at(x, y);
                o[0] = t[0], o[1] = t[1], o[2] = t[2];
                continue;
            }
            const Rgb r = filteredRadiance(borderedChain, octahedralDirection((x + 0.5) / side, (y + 0.5) / side), samples);
            o[0] = float(r.r), o[1] = float(r.g), o[2] = float(r.b);
        }
    });
    writeBordered(inner, out);
}

/// Luminance weights of linear Rec. 709 RGB.
double luminance(const glm::vec3& c) { return 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b; }

/// The dominant light and the irradiance without it (EnvironmentLight::dominantDirection).
void separateDominantLight(EnvironmentLight& e) {
    const glm::vec3(&c)[9] = e.shIrradiance;
    std::copy_n(c, 9, e.shIrradianceLessDominant);
    // The linear band is c[3] x + c[1] y + c[2] z per channel (irradianceAt's order).
    const glm::dvec3 axis(luminance(c[3]), luminance(c[1]), luminance(c[2]));
    if (!(glm::dot(axis, axis) > 0.0)) return;  // no direction stands out: no light
    const glm::dvec3 d = glm::normalize(axis);
    e.dominantDirection = glm::vec3(d);
    glm::vec3 intensity;
    for (int k = 0; k < 3; ++k) intensity[k] = float(std::max(0.0, 2.0 * (c[3][k] * d.x + c[1][k] * d.y + c[2][k] * d.z)));
    e.dominantIntensity = intensity;
    // The light's bands: I/4, (I/2) n.d, and (5 I / 32)(3 (n.d)² - 1) written in the polynomials
    // xy, yz, 3z² - 1, xz, x² - y² (with x² + y² + z² = 1).
    const glm::vec3 i = intensity;
    const glm::vec3 band2 = i * (5.0f / 32.0f);
    glm::vec3(&r)[9] = e.shIrradianceLessDominant;
    r[0] -= i * 0.25f;
    r[1] -= i * (0.5f * float(d.y)), r[2] -= i * (0.5f * float(d.z)), r[3] -= i * (0.5f * float(d.x));
    r[4] -= band2 * float(6.0 * d.x * d.y);
    r[5] -= band2 * float(6.0 * d.y * d.z);
    r[6] -= band2 * float((3.0 * d.z * d.z - 1.0) / 2.0);
    r[7] -= band2 * float(6.0 * d.x * d.z);
    r[8] -= band2 * float(1.5 * (d.x * d.x - d.y * d.y));
}

}  // namespace

struct EnvironmentPreparation {
    static EnvironmentLight prepare(int width, int height, const float* rgb, float intensity) {
        EnvironmentLight e;
        EnvironmentLight::dfgTable();  // made now, not in the first frame that shades with it
        const Image map = cleanedSource(width, height, rgb, intensity);
        projectIrradiance(map, e.shIrradiance);
        separateDominantLight(e);
        const std::vector<Image> chain = octahedralChain(map);
        std::vector<BorderedLevel> borderedChain;
        for (const Image& level : chain) borderedChain.push_back(bordered(level));
        size_t floats = 0;
        for (int k = 0; k < EnvironmentLight::kSpecularLevels; ++k) {
            e.levelOffset_[k] = int(floats);
            const size_t stride = size_t(e.levelSide(k)) + 2;
            floats += stride * stride * 3;
        }
        e.texels_.resize(floats);
        for (int k = 0; k < EnvironmentLight::kSpecularLevels; ++k) fillLevel(chain, borderedChain, k, e.texels_.data() + size_t(e.levelOffset_[k]));
        return e;
    }
};

EnvironmentLight EnvironmentLight::fromEquirectangular(int width, int height, const float* rgb, float intensity) {
    return EnvironmentPreparation::prepare(width, height, rgb, intensity);
}

namespace {

/// The built-in studio's light sources, all in linear radiance. A white Lambertian surface facing
/// the default camera (azimuth 30, elevation 20: scene/camera.h) shows about 1, display white,
/// as the default key light and ambient show one facing the light (0.97): a model's albedo reads
/// as itself. Facing the key it shows about 1.3, facing the floor a quarter of that.
struct SoftBox {
    glm::dvec3 towards;   // from the model
    double halfAngleRadians;
    double radiance;
};
constexpr double kDomeAbove = 0.75, kDomeBelow = 0.22;  // grey dome: the zenith and the floor
const SoftBox kStudioBoxes[] = {
    {{-0.55, 0.65, 0.55}, 0.30, 10.0},  // key: above, in front, to the left
    {{0.85, 0.25, 0.45}, 0.26, 3.5},    // fill: low, to the right
    {{0.25, 0.55, -0.80}, 0.20, 5.0},   // rim: behind and above
};
/// The boxes' edges soften over this fraction of their half angle, so reflections of them on
/// smooth surfaces have no aliased rim.
constexpr double kSoftEdge = 0.15;

glm::vec3 studioRadiance(const glm::dvec3& d) {
    const double t = std::clamp((d.y + 0.3) / 0.9, 0.0, 1.0);
    const double dome = kDomeBelow + (kDomeAbove - kDomeBelow) * t * t * (3.0 - 2.0 * t);
    double l = dome;
    for (const SoftBox& box : kStudioBoxes) {
        const double angle = std::acos(std::clamp(glm::dot(d, glm::normalize(box.towards)), -1.0, 1.0));
        const double edge = std::clamp((box.halfAngleRadians - angle) / (kSoftEdge * box.halfAngleRadians), 0.0, 1.0);
        l += box.radiance * edge;
    }
    return glm::vec3(float(l));
}

}  // namespace

EnvironmentLight EnvironmentLight::neutral(float intensity) {
    constexpr int kWidth = 1024, kHeight = 512;
    std::vector<float> rgb(size_t(kWidth) * kHeight * 3);
    forEachRow(kHeight, [&](int y) {
        for (int x = 0; x < kWidth; ++x) {
            const glm::vec3 c = studioRadiance(equirectDirection((x + 0.5) / kWidth, (y + 0.5) / kHeight));
            float* o = rgb.data() + 3 * (size_t(y) * kWidth + size_t(x));
            o[0] = c.r, o[1] = c.g, o[2] = c.b;
        }
    });
    return fromEquirectangular(kWidth, kHeight, rgb.data(), intensity);
}

const float* EnvironmentLight::dfgTable() {
    static const std::vector<float> table = [] {
        constexpr int n = kDfgTableSide;
        std::vector<float> t(size_t(2 * n * n));
        forEachRow(n, [&](int j) {  // each entry on its own: the same bits at any thread count
            // The shade stage floors roughness at 0.03 and n.v at 1e-4; so do the entries.
            const double roughness = std::max(0.03, double(j) / (n - 1)), alpha = roughness * roughness, a2 = alpha * alpha;
            for (int i = 0; i < n; ++i) {
                const double nDotV = std::max(1e-4, double(i) / (n - 1));
                const glm::dvec3 v(std::sqrt(1.0 - nDotV * nDotV), 0.0, nDotV);
                double a = 0, b = 0;
                for (int k = 0; k < kDfgSamples; ++k) {
                    const glm::dvec3 h = ggxHalfVector(hammersley(uint32_t(k), kDfgSamples), alpha);
                    const double vDotH = glm::dot(v, h);
                    const glm::dvec3 l = 2.0 * vDotH * h - v;
                    const double nDotL = l.z, nDotH = h.z;
                    if (nDotL <= 0.0 || vDotH <= 0.0) continue;
                    // f cos / pdf with pdf = D n.h / (4 v.h): the height-correlated Smith V
                    // (raster/shade.h, specularLobe) times 4 n.l v.h / n.h, split by Schlick.
                    const double vis = 0.5 / (nDotL * std::sqrt(nDotV * nDotV * (1.0 - a2) + a2) +
                                              nDotV * std::sqrt(nDotL * nDotL * (1.0 - a2) + a2));
                    const double g = vis * 4.0 * nDotL * vDotH / nDotH;
                    const double fc = std::pow(1.0 - vDotH, 5.0);
                    a += (1.0 - fc) * g, b += fc * g;
                }
                t[size_t(2 * (j * n + i))] = float(a / kDfgSamples);
                t[size_t(2 * (j * n + i) + 1)] = float(b / kDfgSamples);
            }
        });
        return t;
    }();
    return table.data();
}

}  // namespace cuberille::raster
