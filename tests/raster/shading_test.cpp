// The shade stage's models against slow references written out here in double precision:
// the metallic-roughness BRDF, point and spot light fall-off, normal maps, texture transforms
// and filters, double-sided normals, and the per-effect counters that prove a stage a draw
// does not need never ran.

#include <algorithm>
#include <bit>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "raster/pipeline.h"
#include "raster/resolve.h"
#include "raster/sheen_lobe.h"
#include "raster/texture.h"
#include "scene/scene.h"
#include "tests/raster/test_support.h"

namespace cuberille::testing {
namespace {

using raster::DrawCall;
using raster::Light;
using raster::LightType;
using raster::ShadingModel;
using raster::Texture;

constexpr int kSize = 16;

/// A window-space quad over the whole 16x16 frame at depth 0.5, counter-clockwise on screen
/// (front-facing), normal towards the viewer (-z: window z grows away from the eye), with a
/// UV over [0, 1]².
struct Quad {
    std::vector<glm::vec3> positions = {{0, 0, 0.5f},         {0, kSize, 0.5f}, {kSize, kSize, 0.5f},
                                        {0, 0, 0.5f},         {kSize, kSize, 0.5f}, {kSize, 0, 0.5f}};
    std::vector<glm::vec2> uvs = {{0, 0}, {0, 1}, {1, 1}, {0, 0}, {1, 1}, {1, 0}};
    std::vector<glm::vec3> normals = std::vector<glm::vec3>(6, glm::vec3(0, 0, -1));
    std::vector<glm::vec4> tangents = std::vector<glm::vec4>(6, glm::vec4(1, 0, 0, 1));

    DrawCall call(ShadingModel model) const {
        DrawCall d;
        d.space = raster::PositionSpace::Window;
        d.positions = positions;
        d.normals = normals;
        d.texCoords = uvs;
        d.tangents = tangents;
        d.state.shading = model;
        d.state.cull = raster::CullMode::None;
        return d;
    }
};

ResolvedDraw render(const DrawCall& d) { return renderResolved(d, kSize, kSize); }

glm::vec4 at(const raster::Image& image, int x, int y) {
    const float* p = image.pixel(x, y);
    return {p[0], p[1], p[2], p[3]};
}

Light directionalLight(const glm::vec3& travelling, const glm::vec3& intensity) {
    Light l;
    l.direction = glm::normalize(travelling);
    l.intensity = intensity;
    return l;
}

// glTF 2.0 appendix B, in double, with our light units (intensity = pi x irradiance). The
// shader is float and writes the GGX denominator without cancellation, so even a sharp
// highlight (roughness 0.1) agrees to 2 parts in 10^4.
// From the BRDF's inputs: c_diff, F0, alpha (roughness²) and F90.
glm::dvec3 referenceBrdfOfInputs(glm::dvec3 diffuse, glm::dvec3 f0, double a, glm::dvec3 n, glm::dvec3 v, glm::dvec3 l,
                                 glm::dvec3 intensity, double f90 = 1.0) {
    const double a2 = a * a;
    const glm::dvec3 h = glm::normalize(l + v);
    const double nl = glm::dot(n, l), nv = glm::dot(n, v), nh = glm::dot(n, h), vh = glm::dot(v, h);
    if (nl <= 0.0) return glm::dvec3(0.0);
    const glm::dvec3 f = f0 + (f90 - f0) * std::pow(1.0 - vh, 5.0);
    const double d = a2 / (M_PI * std::pow(nh * nh * (a2 - 1.0) + 1.0, 2.0));
    const double vis = 0.5 / (nl * std::sqrt(nv * nv * (1 - a2) + a2) + nv * std::sqrt(nl * nl * (1 - a2) + a2));
    return intensity * nl * ((1.0 - f) * diffuse + M_PI * f * d * vis);
}

glm::dvec3 referenceBrdf(glm::dvec3 albedo, double metallic, double roughness, glm::dvec3 n, glm::dvec3 v,
                         glm::dvec3 l, glm::dvec3 intensity, double ior = 1.5) {
    const double dielectric = std::pow((ior - 1.0) / (ior + 1.0), 2.0);  // KHR_materials_ior; 0.04 at 1.5
    return referenceBrdfOfInputs(albedo * (1.0 - metallic), glm::mix(glm::dvec3(dielectric), albedo, metallic),
                                 roughness * roughness, n, v, l, intensity);
}

// The quad as the reference tests draw it: the metallic-roughness model seen from `camera`
// under one sun of intensity 2 from (-0.3, 0.2, -1) (kSunTowards), with `ambient`.
const glm::dvec3 kSunTowards = -glm::normalize(glm::dvec3(0.3, -0.2, 1.0));
DrawCall sunlitQuad(const Quad& quad, const glm::dvec3& camera, float ambient = 0.0f) {
    DrawCall d = quad.call(ShadingModel::MetallicRoughness);
    d.state.cameraPosition = glm::vec3(camera);
    d.state.lighting.lights[0] = directionalLight({0.3f, -0.2f, 1.0f}, glm::vec3(2.0f));
    d.state.lighting.lightCount = 1;
    d.state.lighting.ambient = glm::vec3(ambient);
    return d;
}

// A quad of albedo (0.8, 0.5, 0.2) under one sun, shaded with the metallic-roughness BRDF,
// against referenceBrdf at every pixel.
void expectTheReferenceBrdfAtEveryPixel(float metallic, float roughness, float ior) {
    const Quad quad;
    const glm::dvec3 camera(8.0, 8.0, -20.0);
    DrawCall d = sunlitQuad(quad, camera);
    d.state.constantColor = glm::vec4(0.8f, 0.5f, 0.2f, 1.0f);
    d.state.metallic = metallic;
    d.state.roughness = roughness;
    d.state.dielectricF0 = scene::dielectricReflectance(ior);
    const raster::Image img = render(d).image;
    for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize; ++x) {
            const glm::dvec3 p(x + 0.5, y + 0.5, 0.5);
            const glm::dvec3 expected = referenceBrdf(glm::dvec3(0.8, 0.5, 0.2), metallic, roughness, glm::dvec3(0, 0, -1),
                                                      glm::normalize(camera - p),
                                                      kSunTowards, glm::dvec3(2.0), ior);
            for (int c = 0; c < 3; ++c)
                ASSERT_NEAR(at(img, x, y)[c], expected[c], 2e-4 * std::max(1.0, expected[c]))
                    << "metallic " << metallic << " roughness " << roughness << " ior " << ior << " at " << x << "," << y;
        }
}

TEST(MetallicRoughness, MatchesTheReferenceBrdfAtEveryPixel) {
    for (const auto& [metallic, roughness] : {std::pair{0.0f, 0.5f}, {1.0f, 0.3f}, {0.5f, 1.0f}, {0.0f, 0.1f}})
        expectTheReferenceBrdfAtEveryPixel(metallic, roughness, 1.5f);
}

// KHR_materials_ior: the dielectric reflectance from the index of refraction, against the same
// double-precision reference at every pixel, for water, diamond and the special value 0 (F0 = 1),
// half-metallic too (the mix towards the albedo).
TEST(MetallicRoughness, IndexOfRefractionSetsTheDielectricReflectanceAsTheReferenceDoes) {
    for (const auto& [ior, metallic] : {std::pair{1.33f, 0.0f}, {2.42f, 0.0f}, {0.0f, 0.0f}, {2.42f, 0.5f}})
        expectTheReferenceBrdfAtEveryPixel(metallic, 0.3f, ior);
}

// KHR_materials_pbrSpecularGlossiness: the same BRDF from the extension's inputs, c_diff =
// diffuse (1 - max(specular)), F0 = specular, alpha = (1 - glossiness)², plus the ambient term
// ambient (c_diff + F0), against the double-precision reference at every pixel: a dielectric, a
// coloured metal (gold: black diffuse) and a rough plastic. The effect counter counts exactly its
// pixels, and a metallic-roughness draw none.
TEST(SpecularGlossiness, MatchesTheReferenceBrdfAtEveryPixel) {
    struct Material {
        glm::vec3 diffuse, specular;
        float glossiness;
    };
    for (const Material& mat : {Material{{0.8f, 0.5f, 0.2f}, {0.04f, 0.04f, 0.04f}, 0.7f},
                                Material{{0.0f, 0.0f, 0.0f}, {1.0f, 0.766f, 0.336f}, 0.9f},
                                Material{{0.2f, 0.6f, 0.9f}, {0.3f, 0.2f, 0.1f}, 0.0f}}) {
        const Quad quad;
        const glm::dvec3 camera(8.0, 8.0, -20.0);
        DrawCall d = sunlitQuad(quad, camera, 0.1f);
        d.state.constantColor = glm::vec4(mat.diffuse, 1.0f);
        d.state.brdf.specularGlossiness = true;
        d.state.brdf.specularFactor = mat.specular;
        d.state.brdf.glossiness = mat.glossiness;
        d.state.metallic = 0.5f, d.state.roughness = 0.2f;  // not read
        const ResolvedDraw r = render(d);
        EXPECT_EQ(r.counters.specularGlossinessPixels, r.counters.pixelsShaded);
        EXPECT_GT(r.counters.pixelsShaded, 0u);
        const glm::dvec3 specular(mat.specular);
        const glm::dvec3 diffuse = glm::dvec3(mat.diffuse) * (1.0 - std::max({specular.r, specular.g, specular.b}));
        const double rough = std::max(0.03, 1.0 - double(mat.glossiness));  // the shader's roughness floor
        for (int y = 0; y < kSize; ++y)
            for (int x = 0; x < kSize; ++x) {
                const glm::dvec3 p(x + 0.5, y + 0.5, 0.5);
                const glm::dvec3 expected =
                    0.1 * (diffuse + specular) +
                    referenceBrdfOfInputs(diffuse, specular, rough * rough, glm::dvec3(0, 0, -1), glm::normalize(camera - p),
                                          kSunTowards, glm::dvec3(2.0));
                for (int c = 0; c < 3; ++c)
                    ASSERT_NEAR(at(r.image, x, y)[c], expected[c], 2e-4 * std::max(1.0, expected[c]))
                        << "glossiness " << mat.glossiness << " at " << x << "," << y;
            }
    }
    const Quad quad;
    EXPECT_EQ(render(quad.call(ShadingModel::MetallicRoughness)).counters.specularGlossinessPixels, 0u);
}

// KHR_materials_specular: the dielectric reflection's F0 = min(0.04 x colour, 1) x strength and
// F90 = strength, mixed towards the metal's by metallic, against the double-precision reference
// at every pixel: no specular at all (a purely diffuse surface), a tinted one, a colour factor
// past 1 (F0 clamped to 1 before the strength), half metallic. Its effect counter counts exactly
// its pixels.
TEST(DielectricSpecular, MatchesTheReferenceBrdfAtEveryPixel) {
    struct Material {
        float strength;
        glm::vec3 color;
        float metallic;
    };
    for (const Material& mat : {Material{0.0f, {1.0f, 1.0f, 1.0f}, 0.0f}, Material{1.0f, {1.0f, 0.5f, 0.2f}, 0.0f},
                                Material{0.7f, {30.0f, 10.0f, 1.0f}, 0.0f}, Material{0.5f, {0.2f, 1.0f, 0.6f}, 0.5f}}) {
        const Quad quad;
        const glm::dvec3 camera(8.0, 8.0, -20.0);
        DrawCall d = sunlitQuad(quad, camera);
        d.state.constantColor = glm::vec4(0.8f, 0.5f, 0.2f, 1.0f);
        d.state.metallic = mat.metallic;
        d.state.roughness = 0.3f;
        d.state.brdf.dielectricSpecular = true;
        d.state.brdf.specularStrength = mat.strength;
        d.state.brdf.specularColor = mat.color;
        const ResolvedDraw r = render(d);
        EXPECT_EQ(r.counters.dielectricSpecularPixels, r.counters.pixelsShaded);
        const glm::dvec3 albedo(0.8, 0.5, 0.2);
        const glm::dvec3 dielectricF0 = glm::min(0.04 * glm::dvec3(mat.color), glm::dvec3(1.0)) * double(mat.strength);
        const double metallic = mat.metallic;
        const glm::dvec3 f0 = glm::mix(dielectricF0, albedo, metallic);
        const double f90 = mat.strength + (1.0 - mat.strength) * metallic;
        for (int y = 0; y < kSize; ++y)
            for (int x = 0; x < kSize; ++x) {
                const glm::dvec3 p(x + 0.5, y + 0.5, 0.5);
                const glm::dvec3 expected =
                    referenceBrdfOfInputs(albedo * (1.0 - metallic), f0, 0.09, glm::dvec3(0, 0, -1), glm::normalize(camera - p),
                                          kSunTowards, glm::dvec3(2.0), f90);
                for (int c = 0; c < 3; ++c)
                    ASSERT_NEAR(at(r.image, x, y)[c], expected[c], 2e-4 * std::max(1.0, expected[c]))
                        << "strength " << mat.strength << " at " << x << "," << y;
            }
    }
    const Quad quad;
    EXPECT_EQ(render(quad.call(ShadingModel::MetallicRoughness)).counters.dielectricSpecularPixels, 0u);
}

// KHR_materials_clearcoat: the coated material is the material — ambient, light and emission —
// times 1 - w, plus the coat, with w = clearcoat x (0.04 + 0.96 (1 - n_c.v)^5) and the coat
// ambient x w plus, per light, E n_c.l pi D V w at the coat's roughness: against the
// double-precision reference at every pixel, a full and a half coat, under a normal map that
// tilts the base's normal but not the coat's (which follows the surface), and under a coat normal
// map that tilts the coat's but not the base's. The counter counts exactly the coated pixels, and
// an uncoated draw none.
TEST(Clearcoat, LaysTheReferenceCoatOverTheMaterialAtEveryPixel) {
    const float s = std::sin(float(M_PI) / 3), c = std::cos(float(M_PI) / 3);
    struct Case {
        float clearcoat;
        bool normalMapped;  // tangent-space (sin 60°, 0, cos 60°): world (sin 60°, 0, -cos 60°)
        bool coatMapped;    // the same map as the coat's own
    };
    for (const Case k : {Case{1.0f, false, false}, Case{0.5f, false, false}, Case{1.0f, true, false}, Case{1.0f, false, true}}) {
        const Quad quad;
        const glm::dvec3 camera(8.0, 8.0, -20.0);
        const Texture map(1, 1, {glm::vec4(0.5f * s + 0.5f, 0.5f, 0.5f * c + 0.5f, 1.0f)});
        DrawCall d = sunlitQuad(quad, camera, 0.1f);
        if (k.normalMapped) d.state.textures.normal.texture = &map;
        if (k.coatMapped) d.state.textures.clearcoatNormal.texture = &map;
        d.state.constantColor = glm::vec4(0.8f, 0.5f, 0.2f, 1.0f);
        d.state.metallic = 0.0f;
        d.state.roughness = 0.6f;
        d.state.brdf.clearcoat = k.clearcoat;
        d.state.brdf.clearcoatRoughness = 0.1f;
        d.state.emissive = glm::vec3(0.05f, 0.1f, 0.0f);
        const ResolvedDraw r = render(d);
        EXPECT_EQ(r.counters.clearcoatPixels, r.counters.pixelsShaded);
        const glm::dvec3 albedo(0.8, 0.5, 0.2), toLight = kSunTowards, surface(0, 0, -1), tilted = glm::normalize(glm::dvec3(s, 0.0, -c));
        const glm::dvec3 base = k.normalMapped ? tilted : surface, coatNormal = k.coatMapped ? tilted : surface;
        for (int y = 0; y < kSize; ++y)
            for (int x = 0; x < kSize; ++x) {
                const glm::dvec3 p(x + 0.5, y + 0.5, 0.5), v = glm::normalize(camera - p);
                const glm::dvec3 material = 0.1 * (albedo + 0.04) + glm::dvec3(0.05, 0.1, 0.0) +
                                            referenceBrdf(albedo, 0.0, 0.6, base, v, toLight, glm::dvec3(2.0));
                const double w = k.clearcoat * (0.04 + 0.96 * std::pow(1.0 - glm::dot(coatNormal, v), 5.0));
                const glm::dvec3 coat =
                    0.1 * w + w * referenceBrdfOfInputs(glm::dvec3(0.0), glm::dvec3(1.0), 0.01, coatNormal, v, toLight, glm::dvec3(2.0));
                const glm::dvec3 expected = material * (1.0 - w) + coat;
                for (int ch = 0; ch < 3; ++ch)
                    ASSERT_NEAR(at(r.image, x, y)[ch], expected[ch], 2e-4 * std::max(1.0, expected[ch]))
                        << "clearcoat " << k.clearcoat << (k.normalMapped ? " normal-mapped" : "") << (k.coatMapped ? " coat-mapped" : "")
                        << " at " << x << "," << y;
            }
    }
    const Quad quad;
    EXPECT_EQ(render(quad.call(ShadingModel::MetallicRoughness)).counters.clearcoatPixels, 0u);
}

// The sheen lobe's directional albedo as the shade stage reads it, against the integral taken 6x
// finer (within 1e-4 of 800 steps), on a 40 x 40 grid of (n.v, roughness) wherever E <= 1 (above,
// the dimming clamps at max(colour) = 1 and the error does not show): within 0.004, the measured
// 0.0035 and a margin.
TEST(SheenLobe, AlbedoTableMatchesAFineIntegral) {
    const float* table = raster::sheenAlbedoTable();
    int compared = 0;
    for (int a = 0; a < 40; ++a)
        for (int b = 0; b < 40; ++b) {
            const double nDotV = 0.003 + a / 40.0, roughness = raster::kSheenRoughnessFloor + (1.0 - raster::kSheenRoughnessFloor) * b / 39.0;
            const double reference = raster::sheenAlbedoIntegral(nDotV, roughness, 96);
            if (reference > 1.0) continue;
            ++compared;
            ASSERT_NEAR(raster::sheenAlbedo(table, float(nDotV), float(roughness)), reference, 0.004)
                << "n.v " << nDotV << " roughness " << roughness;
        }
    EXPECT_GT(compared, 1500);
}

// KHR_materials_sheen, against a double-precision reference at every pixel: the material (ambient,
// one sun, emission) dimmed by 1 - max(c) E(n.v, r), plus the sheen's ambient c E and its light E
// n.l pi D V c, for a smooth and a rough, a white and a coloured sheen, and under a clear coat. E
// comes from the fine integral, so the tolerance is the table's 0.004 times what E multiplies (the
// material and the sheen's ambient) over the float shader's 2e-4.
TEST(Sheen, LaysTheReferenceSheenOverTheMaterialAtEveryPixel) {
    struct Case {
        glm::vec3 color;
        float roughness;
        float clearcoat;
    };
    for (const Case k : {Case{glm::vec3(1.0f), 0.3f, 0.0f}, Case{glm::vec3(0.9f, 0.4f, 0.1f), 0.8f, 0.0f},
                         Case{glm::vec3(1.0f), 0.05f, 0.0f}, Case{glm::vec3(0.5f), 0.5f, 1.0f}}) {
        const Quad quad;
        const glm::dvec3 camera(8.0, 30.0, -6.0);  // a glancing view: the sheen's side of the lobe
        DrawCall d = sunlitQuad(quad, camera, 0.1f);
        d.state.constantColor = glm::vec4(0.8f, 0.5f, 0.2f, 1.0f);
        d.state.metallic = 0.0f;
        d.state.roughness = 0.6f;
        d.state.emissive = glm::vec3(0.05f, 0.1f, 0.0f);
        d.state.brdf.sheenColor = k.color;
        d.state.brdf.sheenRoughness = k.roughness;
        d.state.brdf.clearcoat = k.clearcoat;
        d.state.brdf.clearcoatRoughness = 0.1f;
        const ResolvedDraw r = render(d);
        EXPECT_EQ(r.counters.sheenPixels, r.counters.pixelsShaded);
        const glm::dvec3 albedo(0.8, 0.5, 0.2), toLight = kSunTowards, n(0, 0, -1), c(k.color);
        const double roughness = std::max(double(raster::kSheenRoughnessFloor), double(k.roughness)), alpha = roughness * roughness;
        for (int y = 0; y < kSize; ++y)
            for (int x = 0; x < kSize; ++x) {
                const glm::dvec3 p(x + 0.5, y + 0.5, 0.5), v = glm::normalize(camera - p);
                const double nv = glm::dot(n, v), nl = glm::dot(n, toLight), nh = glm::dot(n, glm::normalize(toLight + v));
                const double e = raster::sheenAlbedoIntegral(nv, roughness, 96);
                const double scale = std::clamp(1.0 - std::max({c.r, c.g, c.b}) * e, 0.0, 1.0);
                const double distribution = (2.0 + 1.0 / alpha) * std::pow(1.0 - nh * nh, 0.5 / alpha) / (2.0 * M_PI);
                const double visibility = 1.0 / (4.0 * (nl + nv - nl * nv));
                const glm::dvec3 sheen = 0.1 * c * e + 2.0 * nl * M_PI * distribution * visibility * c;
                const glm::dvec3 material = 0.1 * (albedo + 0.04) + referenceBrdf(albedo, 0.0, 0.6, n, v, toLight, glm::dvec3(2.0));
                glm::dvec3 expected = material * scale + sheen + glm::dvec3(0.05, 0.1, 0.0);
                if (k.clearcoat > 0.0f) {
                    const double w = k.clearcoat * (0.04 + 0.96 * std::pow(1.0 - nv, 5.0));
                    expected = expected * (1.0 - w) + 0.1 * w +
                               w * referenceBrdfOfInputs(glm::dvec3(0.0), glm::dvec3(1.0), 0.01, n, v, toLight, glm::dvec3(2.0));
                }
                for (int ch = 0; ch < 3; ++ch)
                    ASSERT_NEAR(at(r.image, x, y)[ch], expected[ch],
                                0.004 * (std::max({material.r, material.g, material.b}) * std::max({c.r, c.g, c.b}) + 0.1 * c[ch]) +
                                    2e-4 * std::max(1.0, expected[ch]))
                        << "sheen " << k.color.r << "," << k.color.g << "," << k.color.b << " roughness " << k.roughness
                        << " coat " << k.clearcoat << " at " << x << "," << y;
            }
    }
    const Quad quad;
    EXPECT_EQ(render(quad.call(ShadingModel::MetallicRoughness)).counters.sheenPixels, 0u);
}

// KHR_materials_transmission (and _volume), against a double-precision reference at every pixel:
// a transmissive quad over an unlit backdrop B gives R + T B, R the material with its diffuse lobe
// kept at 1 - t (ambient and the sun), T = t c_diff (1 - F(n.v)) x attenuationColor^(d /
// distance); over nothing (a transparent clear), R with alpha 1 - mean(T). Thin-walled and with a
// volume, a whole and a half share, blended at alpha 0.5 (a R + (a T + 1 - a) B), and under a
// clear coat of weight w, which dims R and T alike by 1 - w and adds its own light. The counter
// counts exactly the transmissive pixels, and an opaque draw none.
TEST(Transmission, ComposesTheReferenceOverWhatIsBehindAtEveryPixel) {
    struct Case {
        float transmission;
        float thickness;  // 0: thin-walled
        float alpha;      // < 1: blended
        float clearcoat = 0.0f;
    };
    const glm::dvec3 backdrop(0.2, 0.6, 0.9), attenuationColor(0.5, 0.8, 1.0);
    const double attenuationDistance = 1.5;
    for (const Case k :
         {Case{1.0f, 0.0f, 1.0f}, Case{0.5f, 0.0f, 1.0f}, Case{1.0f, 2.0f, 1.0f}, Case{1.0f, 0.0f, 0.5f}, Case{1.0f, 0.0f, 1.0f, 1.0f}}) {
        for (const bool withBackdrop : {true, false}) {
            const Quad quad;
            Quad far;
            for (glm::vec3& p : far.positions) p.z = 0.9f;
            DrawCall back = far.call(ShadingModel::Unlit);
            back.state.constantColor = glm::vec4(glm::vec3(backdrop), 1.0f);
            const glm::dvec3 camera(8.0, 8.0, -20.0);
            DrawCall glass = sunlitQuad(quad, camera, 0.1f);
            glass.state.constantColor = glm::vec4(0.8f, 0.5f, 0.2f, k.alpha);
            glass.state.metallic = 0.0f;
            glass.state.roughness = 0.4f;
            glass.state.brdf.transmission = k.transmission;
            glass.state.brdf.thickness = k.thickness;
            glass.state.brdf.attenuationColor = glm::vec3(attenuationColor);
            glass.state.brdf.attenuationDistance = float(attenuationDistance);
            glass.state.brdf.clearcoat = k.clearcoat;
            glass.state.brdf.clearcoatRoughness = 0.1f;
            glass.state.depthWrite = false;
            if (k.alpha < 1.0f) glass.state.alphaMode = raster::AlphaMode::Blend;
            raster::Pipeline p;
            p.beginFrame(frame(kSize, kSize, 1));
            if (withBackdrop) p.draw(back);
            p.draw(glass);
            p.endFrame();
            raster::Image image;
            raster::resolveColor(p.framebuffer(), image);
            EXPECT_EQ(p.stats().counters.transmissionPixels, uint64_t(kSize) * kSize);
            const glm::dvec3 albedo(0.8, 0.5, 0.2), n(0, 0, -1);
            const double t = k.transmission, a = k.alpha;
            for (int y = 0; y < kSize; ++y)
                for (int x = 0; x < kSize; ++x) {
                    const glm::dvec3 pixel(x + 0.5, y + 0.5, 0.5), v = glm::normalize(camera - pixel);
                    const double fresnel = 0.04 + 0.96 * std::pow(1.0 - glm::dot(n, v), 5.0);
                    glm::dvec3 through = t * albedo * (1.0 - fresnel);
                    if (k.thickness > 0.0f)
                        for (int c = 0; c < 3; ++c) through[c] *= std::pow(attenuationColor[c], k.thickness / attenuationDistance);
                    glm::dvec3 own = 0.1 * (albedo * (1.0 - t) + 0.04) +
                                     referenceBrdfOfInputs(albedo * (1.0 - t), glm::dvec3(0.04), 0.16, n, v, kSunTowards, glm::dvec3(2.0));
                    if (k.clearcoat > 0.0f) {
                        const double w = k.clearcoat * fresnel;
                        own = own * (1.0 - w) + 0.1 * w +
                              w * referenceBrdfOfInputs(glm::dvec3(0.0), glm::dvec3(1.0), 0.01, n, v, kSunTowards, glm::dvec3(2.0));
                        through *= 1.0 - w;
                    }
                    const glm::dvec3 seen = a * through + (1.0 - a);
                    const glm::dvec3 behind = withBackdrop ? backdrop : glm::dvec3(0.0);
                    const glm::dvec3 expected = a * own + seen * behind;
                    const double alpha = 1.0 - (seen.r + seen.g + seen.b) / 3.0 * (withBackdrop ? 0.0 : 1.0);
                    for (int ch = 0; ch < 3; ++ch)
                        ASSERT_NEAR(at(image, x, y)[ch], expected[ch], 2e-4 * std::max(1.0, expected[ch]))
                            << "transmission " << t << " thickness " << k.thickness << " alpha " << a << " coat " << k.clearcoat
                            << (withBackdrop ? " over the backdrop" : " over nothing") << " at " << x << "," << y;
                    ASSERT_NEAR(at(image, x, y).a, alpha, 1e-6) << x << "," << y;
                }
        }
    }
    const Quad quad;
    EXPECT_EQ(render(quad.call(ShadingModel::MetallicRoughness)).counters.transmissionPixels, 0u);
}

TEST(MetallicRoughness, AmbientAndEmissiveAddWithoutLights) {
    const Quad quad;
    DrawCall d = quad.call(ShadingModel::MetallicRoughness);
    d.state.constantColor = glm::vec4(0.5f, 0.5f, 0.5f, 1.0f);
    d.state.metallic = 0.0f;
    d.state.lighting.ambient = glm::vec3(0.2f);
    d.state.emissive = glm::vec3(0.1f, 0.0f, 0.3f);
    const ResolvedDraw r = render(d);
    // ambient x (c_diff + F0) + emissive
    const glm::vec3 expected = 0.2f * (0.5f + 0.04f) + glm::vec3(0.1f, 0.0f, 0.3f);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(at(r.image, 3, 5)[c], expected[c], 1e-6f);
    EXPECT_EQ(r.counters.lightEvaluations, 0u);
}

TEST(PunctualLights, PointLightFallsOffWithTheSquareOfDistance) {
    const Quad quad;
    auto brightnessAtCentre = [&](float height) {
        DrawCall d = quad.call(ShadingModel::Lambert);
        Light& l = d.state.lighting.lights[0];
        l.type = LightType::Point;
        l.position = glm::vec3(8.0f, 8.0f, 0.5f - height);  // straight above the pixel corner (8, 8)
        l.intensity = glm::vec3(100.0f);
        d.state.lighting.lightCount = 1;
        const raster::Image img = render(d).image;
        // Pixel (8, 8)'s centre is (0.5, 0.5) away sideways.
        const double r2 = double(height) * height + 0.5;
        const double expected = 100.0 / r2 * (height / std::sqrt(r2));
        EXPECT_NEAR(at(img, 8, 8).r, expected, 1e-4 * expected) << height;
        return at(img, 8, 8).r;
    };
    EXPECT_GT(brightnessAtCentre(5.0f), 3.5f * brightnessAtCentre(10.0f));
}

TEST(PunctualLights, RangeCutsThePointLightOffSmoothly) {
    const Quad quad;
    DrawCall d = quad.call(ShadingModel::Lambert);
    Light& l = d.state.lighting.lights[0];
    l.type = LightType::Point;
    l.position = glm::vec3(0.0f, 0.0f, 0.0f);
    l.intensity = glm::vec3(1.0f);
    l.range = 8.0f;
    d.state.lighting.lightCount = 1;
    const raster::Image img = render(d).image;
    // Every pixel against KHR_lights_punctual's window written out in double: at distance r from
    // the light, (n.l / r²) (clamp(1 - (r/range)^4, 0, 1))², which falls to 0 at the range with a
    // zero slope. The quad lies at z = 0.5 facing the light, so n.l = 0.5 / r.
    int lit = 0, cut = 0;
    for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize; ++x) {
            const glm::dvec3 p(x + 0.5, y + 0.5, 0.5);
            const double r2 = glm::dot(p, p), window = std::clamp(1.0 - (r2 / 64.0) * (r2 / 64.0), 0.0, 1.0);
            const double expected = 0.5 / std::sqrt(r2) / r2 * window * window;
            EXPECT_NEAR(at(img, x, y).r, expected, 2e-6 + 1e-5 * expected) << x << "," << y;
            lit += expected > 0.0, cut += expected == 0.0;
        }
    EXPECT_GT(lit, 20);
    EXPECT_GT(cut, 20) << "the range falls inside the quad";
}

TEST(PunctualLights, SpotLightIsDarkOutsideItsOuterConeAndFullInsideItsInnerCone) {
    const Quad quad;
    DrawCall d = quad.call(ShadingModel::Lambert);
    Light& l = d.state.lighting.lights[0];
    l.type = LightType::Spot;
    l.position = glm::vec3(8.0f, 8.0f, -4.5f);  // 5 above the surface
    l.direction = glm::vec3(0, 0, 1);
    l.intensity = glm::vec3(25.0f);
    l.cosInnerCone = std::cos(0.3f);
    l.cosOuterCone = std::cos(0.6f);
    d.state.lighting.lightCount = 1;
    const raster::Image img = render(d).image;
    // (8, 8) is 0.14 rad off axis (inside the inner cone): the point light's value.
    const double r2 = 25.0 + 0.5;
    EXPECT_NEAR(at(img, 8, 8).r, 25.0 / r2 * (5.0 / std::sqrt(r2)), 1e-4);
    // (15, 15) is atan(7.8 / 5) = 1.0 rad off axis: outside the outer cone.
    EXPECT_EQ(at(img, 15, 15).r, 0.0f);
}

TEST(NormalMap, FlatTexelKeepsTheNormalAndATiltedOneTiltsTheLighting) {
    const Quad quad;
    auto shadeWith = [&](glm::vec3 encodedNormal) {
        const Texture map(1, 1, {glm::vec4(encodedNormal, 1.0f)});
        DrawCall d = quad.call(ShadingModel::Lambert);
        d.state.textures.normal.texture = &map;
        d.state.lighting.lights[0] = directionalLight({0, 0, 1}, glm::vec3(1.0f));  // from the viewer
        d.state.lighting.lightCount = 1;
        const ResolvedDraw r = render(d);
        EXPECT_EQ(r.counters.textureSamples, r.counters.pixelsShaded);
        return at(r.image, 4, 4).r;
    };
    EXPECT_NEAR(shadeWith({0.5f, 0.5f, 1.0f}), 1.0f, 1e-6f);
    // Tangent-space (sin 60°, 0, cos 60°): lit at cos 60° = 0.5.
    const float s = std::sin(float(M_PI) / 3), c = std::cos(float(M_PI) / 3);
    EXPECT_NEAR(shadeWith({0.5f * s + 0.5f, 0.5f, 0.5f * c + 0.5f}), 0.5f, 1e-5f);
}

TEST(DoubleSided, BackFacesAreLitWithTheirNormalReversed) {
    Quad quad;
    std::swap(quad.positions[1], quad.positions[2]);  // both triangles clockwise: back-facing
    std::swap(quad.positions[4], quad.positions[5]);
    std::swap(quad.uvs[1], quad.uvs[2]);
    std::swap(quad.uvs[4], quad.uvs[5]);
    quad.normals.assign(6, glm::vec3(0, 0, 1));  // the front side faces away from the viewer
    DrawCall d = quad.call(ShadingModel::Lambert);
    d.state.lighting.lights[0] = directionalLight({0, 0, 1}, glm::vec3(1.0f));
    d.state.lighting.lightCount = 1;
    EXPECT_NEAR(at(render(d).image, 7, 7).r, 1.0f, 1e-6f);
}

TEST(TextureTransform, OffsetAndRotationMoveTheTexels) {
    // Two texels: red on the left half, green on the right; nearest filtering.
    raster::TextureFilter nearest;
    nearest.magnifyNearest = true;
    nearest.minify = raster::MinFilter::Nearest;
    const Texture t(2, 1, {glm::vec4(1, 0, 0, 1), glm::vec4(0, 1, 0, 1)}, raster::WrapMode::Repeat,
                    raster::WrapMode::Repeat, nearest);
    const Quad quad;
    DrawCall d = quad.call(ShadingModel::Unlit);
    d.state.textures.baseColor.texture = &t;
    EXPECT_EQ(at(render(d).image, 2, 8), glm::vec4(1, 0, 0, 1));
    d.state.textures.baseColor.transform.offset = glm::vec2(0.5f, 0.0f);
    EXPECT_EQ(at(render(d).image, 2, 8), glm::vec4(0, 1, 0, 1)) << "offset by half the width";
    // KHR_texture_transform's rotation by +90°: (u, v) -> (v, -u); the left column reads v.
    const float angle = float(M_PI) / 2;
    d.state.textures.baseColor.transform = {glm::mat2(std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle)),
                                            glm::vec2(0.0f)};
    EXPECT_EQ(at(render(d).image, 2, 2), glm::vec4(1, 0, 0, 1)) << "v < 0.5 lands on u < 0.5";
    EXPECT_EQ(at(render(d).image, 2, 13), glm::vec4(0, 1, 0, 1)) << "v > 0.5 lands on u > 0.5";
}

TEST(TextureFilter, MagnificationAndMinificationFollowTheSampler) {
    const std::vector<glm::vec4> texels = {glm::vec4(0), glm::vec4(1), glm::vec4(1), glm::vec4(0)};  // 2x2
    raster::TextureFilter f;
    const Texture linear(2, 2, texels, raster::WrapMode::ClampToEdge, raster::WrapMode::ClampToEdge, f);
    f.magnifyNearest = true;
    f.minify = raster::MinFilter::NearestMipmapNearest;
    const Texture nearest(2, 2, texels, raster::WrapMode::ClampToEdge, raster::WrapMode::ClampToEdge, f);
    const glm::vec2 between(0.5f, 0.3f);
    EXPECT_EQ(nearest.sample(between, -1.0f), glm::vec4(1)) << "texel (1, 0)";
    EXPECT_NE(linear.sample(between, -1.0f), glm::vec4(1));
    // Minified past level 0 (lod 1, the 1x1 level holds the average).
    EXPECT_EQ(nearest.sample(between, 1.0f), glm::vec4(0.5f));
    EXPECT_EQ(nearest.sample(between, 0.4f), glm::vec4(1)) << "lod 0.4 rounds to level 0";
}

TEST(Effects, AbsentEffectsRunZeroTimes) {
    const Quad quad;
    // Constant colour: nothing interpolated, nothing fetched, nothing lit.
    DrawCall flat = quad.call(ShadingModel::ConstantColor);
    ResolvedDraw r = render(flat);
    EXPECT_EQ(r.counters.pixelsShaded, uint64_t(kSize) * kSize);
    EXPECT_EQ(r.counters.varyingsInterpolated, 0u);
    EXPECT_EQ(r.counters.textureSamples, 0u);
    EXPECT_EQ(r.counters.lightEvaluations, 0u);
    EXPECT_EQ(r.counters.pixelsBlended, 0u);
    EXPECT_EQ(r.counters.pixelsAlphaTested, 0u);
    // Unlit without texture or vertex colours: a constant, nothing interpolated, no lights even
    // if some are set.
    DrawCall unlit = quad.call(ShadingModel::Unlit);
    unlit.state.lighting.lightCount = 1;
    r = render(unlit);
    EXPECT_EQ(r.counters.varyingsInterpolated, 0u);
    EXPECT_EQ(r.counters.lightEvaluations, 0u);
    EXPECT_EQ(r.counters.textureSamples, 0u);
    // Lambert with one directional light: the normal (3 a pixel; the colour is the constant),
    // one light each; with vertex colours they join in.
    DrawCall lit = quad.call(ShadingModel::Lambert);
    lit.state.lighting.lightCount = 1;
    r = render(lit);
    EXPECT_EQ(r.counters.varyingsInterpolated, 3u * kSize * kSize);
    EXPECT_EQ(r.counters.lightEvaluations, uint64_t(kSize) * kSize);
    const std::vector<glm::vec3> colors(6, glm::vec3(0.5f));
    lit.vertexColors = colors;
    r = render(lit);
    EXPECT_EQ(r.counters.varyingsInterpolated, 6u * kSize * kSize);
    EXPECT_EQ(r.counters.lightEvaluations, uint64_t(kSize) * kSize);
    EXPECT_EQ(r.counters.textureSamples, 0u);
    // Present effects are counted: a base colour texture once a pixel, blending once a pixel.
    const Texture white(1, 1, {glm::vec4(1)});
    lit.state.textures.baseColor.texture = &white;
    lit.state.alphaMode = raster::AlphaMode::Blend;
    r = render(lit);
    EXPECT_EQ(r.counters.textureSamples, uint64_t(kSize) * kSize);
    EXPECT_EQ(r.counters.pixelsBlended, uint64_t(kSize) * kSize);
    EXPECT_EQ(r.counters.varyingsInterpolated, 8u * kSize * kSize) << "uv joins normal and colour";
}

TEST(Effects, SceneSubmitsAFlatUnlitMeshAsTheBarePipeline) {
    scene::Scene s;
    scene::Mesh m;
    m.positions = {{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}};
    m.normals.assign(3, glm::vec3(0, 0, 1));
    m.indices = {0, 1, 2};
    m.unlit = true;
    s.meshes.push_back(m);
    s.camera.position = {0, 0, 3};
    raster::Pipeline p;
    p.beginFrame(frame(kSize, kSize, 1));
    s.draw(p, 1.0f);
    p.endFrame();
    EXPECT_GT(p.stats().counters.pixelsShaded, 0u);
    EXPECT_EQ(p.stats().counters.varyingsInterpolated, 0u);
    EXPECT_EQ(p.stats().counters.lightEvaluations, 0u);
}

// Random overlapping triangles in window space for the cross-triangle tests below: of every size
// (most of a few pixels, some large enough for queues of their own between them), with a zero
// normal now and then (a model's len2 > 0 branch shades it black), vertex colours and alphas, and
// texture coordinates that repeat a texture a few times across a triangle or minify it.
struct RandomTriangles {
    static constexpr int kWidth = 150, kHeight = 90, kTriangles = 4000;
    std::vector<glm::vec3> positions, normals, colors;
    std::vector<float> alphas;
    std::vector<glm::vec2> texCoords;
    std::vector<glm::vec4> tangents;  // any direction, either handedness; one now and then along the normal
    int small = 0;
    RandomTriangles() {
        std::mt19937 rng(23);
        std::uniform_real_distribution<float> unit(0.0f, 1.0f), signedUnit(-1.0f, 1.0f);
        for (int i = 0; i < kTriangles; ++i) {
            const float r = unit(rng);
            const float size = r < 0.7f ? 0.3f + 3.7f * unit(rng) : (r < 0.95f ? 4.0f + 8.0f * unit(rng) : 12.0f + 28.0f * unit(rng));
            small += size < 4.0f;
            const glm::vec2 centre(kWidth * unit(rng), kHeight * unit(rng));
            for (int k = 0; k < 3; ++k) {
                positions.push_back({centre.x + size * signedUnit(rng), centre.y + size * signedUnit(rng), 0.05f + 0.9f * unit(rng)});
                normals.push_back(unit(rng) < 0.02f ? glm::vec3(0.0f) : glm::vec3(signedUnit(rng), signedUnit(rng), signedUnit(rng)));
                colors.push_back({unit(rng), unit(rng), unit(rng)});
                alphas.push_back(0.2f + 0.8f * unit(rng));
                texCoords.push_back({3.0f * signedUnit(rng), 3.0f * signedUnit(rng)});
                const float handedness = unit(rng) < 0.5f ? -1.0f : 1.0f;
                tangents.push_back(unit(rng) < 0.02f ? glm::vec4(normals.back(), handedness)
                                                     : glm::vec4(signedUnit(rng), signedUnit(rng), signedUnit(rng), handedness));
            }
        }
    }
};

// The property both cross-triangle queues must keep: the triangles drawn in one draw give the
// image of the same triangles drawn a draw each in the same frame, where no queue ever holds two
// triangles' pixels — the same bits, and the same counts of shaded pixels, light evaluations and
// interpolated varyings. With and without a depth test (the last drawn must win) and blended
// (where the order of output merge shows in every overlap), at 1 and 4 samples. `configure` sets
// the draw's shading model, material and lights; `tangents` gives the vertices tangents (for a
// normal map, which needs texture coordinates too).
template <class Configure>
void expectOneDrawGivesTheImageOfADrawPerTriangle(bool vertexAlphas, bool texCoords, Configure configure, bool tangents = false) {
    static const RandomTriangles scene;
    constexpr int kWidth = RandomTriangles::kWidth, kHeight = RandomTriangles::kHeight;
    ASSERT_GT(scene.small, RandomTriangles::kTriangles / 2);
    for (const bool depthTest : {true, false}) {
        for (const raster::AlphaMode mode : {raster::AlphaMode::Opaque, raster::AlphaMode::Blend}) {
            for (const int samples : {1, 4}) {
                DrawCall all;
                all.space = raster::PositionSpace::Window;
                all.positions = scene.positions, all.normals = scene.normals, all.vertexColors = scene.colors;
                if (vertexAlphas) all.vertexAlphas = scene.alphas;
                if (texCoords) all.texCoords = scene.texCoords;
                if (tangents) all.tangents = scene.tangents;
                all.state.cull = raster::CullMode::None;  // both facings: back faces' normals reversed
                all.state.depthTest = depthTest;
                all.state.alphaMode = mode;
                all.state.constantColor = glm::vec4(1.0f, 1.0f, 1.0f, 0.6f);
                configure(all.state);
                const auto frameOf = [&](bool drawPerTriangle) {
                    raster::Pipeline p;
                    p.beginFrame(frame(kWidth, kHeight, samples));
                    if (!drawPerTriangle) p.draw(all);
                    for (size_t t = 0; drawPerTriangle && t < RandomTriangles::kTriangles; ++t) {
                        DrawCall one = all;
                        one.positions = all.positions.subspan(3 * t, 3);
                        one.normals = all.normals.subspan(3 * t, 3);
                        one.vertexColors = all.vertexColors.subspan(3 * t, 3);
                        if (vertexAlphas) one.vertexAlphas = all.vertexAlphas.subspan(3 * t, 3);
                        if (texCoords) one.texCoords = all.texCoords.subspan(3 * t, 3);
                        if (tangents) one.tangents = all.tangents.subspan(3 * t, 3);
                        p.draw(one);
                    }
                    p.endFrame();
                    ResolvedDraw r;
                    raster::resolveColor(p.framebuffer(), r.image);
                    r.counters = p.stats().counters;
                    return r;
                };
                const ResolvedDraw shared = frameOf(false), alone = frameOf(true);
                const std::string where = std::string(depthTest ? "depth-tested" : "untested") +
                                          (mode == raster::AlphaMode::Blend ? ", blended, " : ", opaque, ") +
                                          std::to_string(samples) + " samples";
                ASSERT_GT(alone.counters.pixelsShaded, uint64_t(kWidth) * kHeight) << where;
                EXPECT_EQ(shared.counters.pixelsShaded, alone.counters.pixelsShaded) << where;
                EXPECT_EQ(shared.counters.lightEvaluations, alone.counters.lightEvaluations) << where;
                EXPECT_EQ(shared.counters.varyingsInterpolated, alone.counters.varyingsInterpolated) << where;
                ASSERT_EQ(shared.image.rgba.size(), alone.image.rgba.size());
                size_t differing = 0;  // bit patterns, so a NaN would count too
                for (size_t c = 0; c < shared.image.rgba.size(); ++c)
                    differing += std::bit_cast<uint32_t>(shared.image.rgba[c]) != std::bit_cast<uint32_t>(alone.image.rgba[c]);
                EXPECT_EQ(differing, 0u) << where;
            }
        }
    }
}

// Small triangles' pixels shade together in their tile's CrossTriangleQueue (raster/shade.h): each
// pixel carries its own triangle's inputs, the queue shades when full, and output merge takes the
// pixels in the order the depth stage queued them, before any later triangle's own queue.
TEST(CrossTriangleShading, OneDrawGivesTheImageOfADrawPerTriangle) {
    expectOneDrawGivesTheImageOfADrawPerTriangle(false, false, [](raster::DrawState& state) {
        state.shading = ShadingModel::Lambert;
        state.lighting.lightCount = 1;
        state.lighting.lights[0] = directionalLight({0.3f, -0.5f, 0.8f}, glm::vec3(2.0f, 1.5f, 1.0f));
        state.lighting.ambient = glm::vec3(0.05f, 0.1f, 0.15f);
    });
}

// Every other draw lights its triangles' pixels across triangles in the tile's InterpolatedQueue
// (raster/shade.h): each triangle interpolates its range of the queue, the textures and lights run
// over the whole queue. Every surface model, with what reads the pixel's place (a shadow mask,
// ambient occlusion), a point light (the interpolated position), vertex alpha and emission; and
// textured: sRGB base colour, UNORM metallic-roughness, occlusion and emissive maps (trilinear,
// so each pixel's level of detail from its own triangle's derivatives), the base colour's under a
// transform of its own; and normal-mapped (each pixel in its own triangle's tangent frame and
// facing: the random triangles come in both windings), with a clear coat's own normal map.
TEST(InterpolatedShading, OneDrawGivesTheImageOfADrawPerTriangle) {
    constexpr int kPixels = RandomTriangles::kWidth * RandomTriangles::kHeight;
    static std::vector<float> shadowMask(kPixels), ambientVisibility(kPixels);
    for (int i = 0; i < kPixels; ++i) shadowMask[i] = float(i % 7) / 6.0f, ambientVisibility[i] = float(i % 5 + 1) / 5.0f;
    Light point;
    point.type = LightType::Point;
    point.position = glm::vec3(60.0f, 40.0f, -30.0f);
    point.intensity = glm::vec3(900.0f, 800.0f, 700.0f);
    auto lights = [&](raster::DrawState& state) {
        state.lighting.lightCount = 2;
        state.lighting.lights[0] = directionalLight({0.3f, -0.5f, 0.8f}, glm::vec3(2.0f, 1.5f, 1.0f));
        state.lighting.lights[0].visibility = shadowMask.data();
        state.lighting.lights[1] = point;
        state.lighting.ambient = glm::vec3(0.05f, 0.1f, 0.15f);
        state.lighting.ambientVisibility = ambientVisibility.data();
        state.emissive = glm::vec3(0.02f, 0.0f, 0.01f);
    };
    {
        SCOPED_TRACE("Lambert, two lights");
        expectOneDrawGivesTheImageOfADrawPerTriangle(true, false, [&](raster::DrawState& state) {
            state.shading = ShadingModel::Lambert;
            lights(state);
        });
    }
    {
        SCOPED_TRACE("MetallicRoughness");
        expectOneDrawGivesTheImageOfADrawPerTriangle(true, false, [&](raster::DrawState& state) {
            state.shading = ShadingModel::MetallicRoughness;
            state.metallic = 0.3f, state.roughness = 0.4f;
            state.cameraPosition = glm::vec3(75.0f, 45.0f, -100.0f);
            lights(state);
        });
    }
    {
        SCOPED_TRACE("Unlit");
        expectOneDrawGivesTheImageOfADrawPerTriangle(true, false, [](raster::DrawState& state) { state.shading = ShadingModel::Unlit; });
    }
    std::mt19937 rng(5);
    std::vector<uint8_t> texels(32 * 32 * 4);
    for (uint8_t& b : texels) b = uint8_t(rng() & 0xff);
    const Texture srgb(32, 32, texels, raster::TexelFormat::Srgb8), unorm(32, 32, texels, raster::TexelFormat::Unorm8);
    {
        SCOPED_TRACE("MetallicRoughness, textured");
        expectOneDrawGivesTheImageOfADrawPerTriangle(true, true, [&](raster::DrawState& state) {
            state.shading = ShadingModel::MetallicRoughness;
            state.cameraPosition = glm::vec3(75.0f, 45.0f, -100.0f);
            lights(state);
            state.textures.baseColor.texture = &srgb;
            state.textures.baseColor.transform.offset = glm::vec2(0.25f, 0.5f);
            state.textures.metallicRoughness.texture = &unorm;
            state.textures.occlusion.texture = &unorm;
            state.textures.emissive.texture = &srgb;
        });
    }
    {
        SCOPED_TRACE("MetallicRoughness, normal-mapped, with a coat's normal map");
        expectOneDrawGivesTheImageOfADrawPerTriangle(
            true, true,
            [&](raster::DrawState& state) {
                state.shading = ShadingModel::MetallicRoughness;
                state.cameraPosition = glm::vec3(75.0f, 45.0f, -100.0f);
                lights(state);
                state.textures.baseColor.texture = &srgb;
                state.textures.normal.texture = &unorm;
                state.normalScale = 0.8f;
                state.brdf.clearcoat = 0.5f, state.brdf.clearcoatRoughness = 0.3f;
                state.textures.clearcoatNormal.texture = &unorm;
                state.textures.clearcoatNormal.transform.offset = glm::vec2(0.5f, 0.125f);
            },
            true);
    }
    {
        SCOPED_TRACE("Lambert, normal-mapped");
        expectOneDrawGivesTheImageOfADrawPerTriangle(
            true, true,
            [&](raster::DrawState& state) {
                state.shading = ShadingModel::Lambert;
                lights(state);
                state.textures.normal.texture = &unorm;
            },
            true);
    }
    {
        SCOPED_TRACE("Unlit, textured");
        expectOneDrawGivesTheImageOfADrawPerTriangle(true, true, [&](raster::DrawState& state) {
            state.shading = ShadingModel::Unlit;
            state.textures.baseColor.texture = &srgb;
        });
    }
}

}  // namespace
}  // namespace cuberille::testing
