// Image-based lighting (raster/environment_light.h) against brute-force integrals in double
// precision over the whole sphere: the irradiance a Lambertian surface shows, the GGX-filtered
// radiance of the specular levels, and the split-sum table against the BRDF's directional
// albedo; then the shade stage's use of them, its counters, and its bits across thread counts
// and instruction sets.

#include <cmath>
#include <cstring>
#include <functional>
#include <random>

#include <gtest/gtest.h>

#include "apps/render_command.h"
#include "raster/environment_light.h"
#include "raster/instruction_set.h"
#include "raster/pipeline.h"
#include "raster/resolve.h"
#include "tests/raster/test_support.h"
#include "tests/thread_counts.h"

namespace cuberille::testing {
namespace {

using raster::EnvironmentLight;
using Radiance = std::function<glm::dvec3(const glm::dvec3&)>;

/// The direction of the equirectangular layout's (u, v), as EnvironmentLight documents it.
glm::dvec3 equirectDirection(double u, double v) {
    const double phi = 2.0 * M_PI * u - M_PI, theta = M_PI * v;
    return {std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi)};
}

EnvironmentLight environmentOf(const Radiance& radiance, int width = 512) {
    const int height = width / 2;
    std::vector<float> rgb(size_t(width) * height * 3);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const glm::dvec3 c = radiance(equirectDirection((x + 0.5) / width, (y + 0.5) / height));
            for (int k = 0; k < 3; ++k) rgb[3 * (size_t(y) * width + x) + k] = float(c[k]);
        }
    return EnvironmentLight::fromEquirectangular(width, height, rgb.data());
}

/// A smooth environment with colour, a vertical gradient, a horizontal one and band-2 detail:
/// positive everywhere, and every channel in the span of the first nine harmonics.
glm::dvec3 smoothSky(const glm::dvec3& d) {
    const double base = 1.0 + 0.4 * d.y + 0.3 * d.x + 0.3 * d.x * d.z;
    return {base, base + 0.2 * d.z, 0.8 * base + 0.3 * d.y * d.y};
}

/// The integral of f over the sphere by the midpoint rule on a theta x phi grid.
glm::dvec3 sphereIntegral(const std::function<glm::dvec3(const glm::dvec3&)>& f, int rows = 720) {
    glm::dvec3 sum(0.0);
    const int columns = 2 * rows;
    for (int j = 0; j < rows; ++j) {
        const double v = (j + 0.5) / rows, dOmega = (2.0 * M_PI / columns) * (M_PI / rows) * std::sin(M_PI * v);
        for (int i = 0; i < columns; ++i) sum += f(equirectDirection((i + 0.5) / columns, v)) * dOmega;
    }
    return sum;
}

glm::dvec3 randomUnit(std::mt19937& rng) {
    std::normal_distribution<double> g;
    // Drawn in a stated order: a constructor's arguments are evaluated in an order compilers
    // choose (GCC right to left, clang left to right), which would test other directions.
    const double x = g(rng), y = g(rng), z = g(rng);
    return glm::normalize(glm::dvec3(x, y, z));
}

/// The GGX distribution D(n.h) for alpha = roughness².
double ggx(double nDotH, double alpha) {
    const double a2 = alpha * alpha, d = nDotH * nDotH * (a2 - 1.0) + 1.0;
    return a2 / (M_PI * d * d);
}

TEST(EnvironmentLight, AConstantEnvironmentLightsAsAnAmbientTermOfItsRadiance) {
    const glm::dvec3 c(0.3, 0.5, 0.7);
    const EnvironmentLight e = environmentOf([&](const glm::dvec3&) { return c; }, 256);
    std::mt19937 rng(7);
    double worstIrradiance = 0, worstSpecular = 0;
    for (int i = 0; i < 200; ++i) {
        const glm::vec3 n(randomUnit(rng));
        const glm::vec3 irradiance = e.irradiance(n);
        for (int k = 0; k < 3; ++k) {
            worstIrradiance = std::max(worstIrradiance, std::fabs(irradiance[k] - c[k]) / c[k]);
            for (float roughness : {0.0f, 0.1f, 0.5f, 0.93f, 1.0f})
                worstSpecular = std::max(worstSpecular, std::fabs(e.specular(n, roughness)[k] - c[k]) / c[k]);
        }
    }
    // Texels carry their exact solid angles, so band 0 is exact; the other harmonics, sampled at
    // texel centres, sum to zero within O(1 / rows²): measured 3.1e-5 of the value at 128 rows.
    EXPECT_LE(worstIrradiance, 3.5e-5);
    // Every filtered texel is a weighted mean of equal values: float rounding alone.
    EXPECT_LE(worstSpecular, 1e-6);
}

// E(n) = (1/pi) x the integral of L(w) max(0, n.w) over the sphere. The environment is in the
// span of the first nine harmonics, so nine coefficients hold it exactly and what is left is the
// discretisation of the map (measured: 2e-4 of the value at most).
TEST(EnvironmentLight, IrradianceMatchesTheCosineIntegralOfTheEnvironment) {
    const EnvironmentLight e = environmentOf(smoothSky);
    std::mt19937 rng(11);
    for (int i = 0; i < 24; ++i) {
        const glm::dvec3 n = randomUnit(rng);
        const glm::dvec3 expected =
            sphereIntegral([&](const glm::dvec3& w) { return smoothSky(w) * std::max(0.0, glm::dot(n, w)); }, 360) / M_PI;
        const glm::vec3 got = e.irradiance(glm::vec3(n));
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(got[k], expected[k], 5e-4 * expected[k]) << "n " << n.x << "," << n.y << "," << n.z;
    }
}

// S(r, roughness) = the integral of L(l) n.l p(l) over the integral of n.l p(l), p(l) = D(h) / 4
// (the lobe's density of l when n = v = r). Filtered importance sampling and bilinear
// octahedral texels approximate it: on this environment, for directions on both sides of the
// octahedral fold (y < 0 reads folded texels and borders), measured within 0.53% at levels 1, 2
// and 4, 0.60% at level 5 and 0.74% at level 3 (the first whose side stops halving, 32); 0.8%
// allowed.
TEST(EnvironmentLight, SpecularLevelsMatchTheGgxFilteredEnvironment) {
    const EnvironmentLight e = environmentOf(smoothSky);
    std::mt19937 rng(13);
    double worst = 0;
    for (int level = 0; level < EnvironmentLight::kSpecularLevels; ++level) {
        const double roughness = double(level) / (EnvironmentLight::kSpecularLevels - 1), alpha = roughness * roughness;
        for (int i = 0; i < 8; ++i) {
            const glm::dvec3 n = randomUnit(rng);
            glm::dvec3 expected;
            if (level == 0) {
                expected = smoothSky(n);
            } else {
                auto weight = [&](const glm::dvec3& l) {
                    const double nl = glm::dot(n, l);
                    if (nl <= 0.0) return 0.0;
                    return nl * ggx(glm::dot(n, glm::normalize(n + l)), alpha);
                };
                const glm::dvec3 num = sphereIntegral([&](const glm::dvec3& l) { return smoothSky(l) * weight(l); }, 720);
                const double den = sphereIntegral([&](const glm::dvec3& l) { return glm::dvec3(weight(l)); }, 720).x;
                expected = num / den;
            }
            const glm::vec3 got = e.specular(glm::vec3(n), float(roughness));
            for (int k = 0; k < 3; ++k) worst = std::max(worst, std::fabs(got[k] - expected[k]) / expected[k]);
        }
        EXPECT_LE(worst, 8e-3) << "level " << level;
        worst = 0;
    }
}

// F0 A + F90 B against the directional albedo of the specular BRDF, the integral over the
// hemisphere of D V F n.l (raster/shade.h's lobe and Schlick's F), for n.v and roughness between
// the table's nodes. The reference integrates over half vectors on a dense midpoint grid in the
// lobe's own measure (u = the GGX's CDF of theta_h, phi), so even a sharp lobe at grazing angles
// is resolved: the table's 1024 Hammersley samples an entry are checked by a different
// quadrature. Measured: A and B within 0.0044 absolute (the table's bilinear steps), 0.0078 at
// grazing n.v (0.05, where the albedo changes fastest between nodes 1/31 apart).
TEST(EnvironmentLight, SplitSumTableMatchesTheBrdfsDirectionalAlbedo) {
    constexpr int kGrid = 1500;
    double worst = 0, worstGrazing = 0;
    for (double nDotV : {0.05, 0.3, 0.62, 0.97})
        for (double roughness : {0.08, 0.35, 0.71, 1.0}) {
            const double alpha = roughness * roughness, a2 = alpha * alpha;
            const glm::dvec3 v(std::sqrt(1.0 - nDotV * nDotV), 0.0, nDotV);
            double scaleA = 0, scaleB = 0;  // the integral's F0 part and its F90 part
            for (int j = 0; j < kGrid; ++j) {
                const double u = (j + 0.5) / kGrid;
                const double cosTheta = std::sqrt((1.0 - u) / (1.0 + (a2 - 1.0) * u)), sinTheta = std::sqrt(1.0 - cosTheta * cosTheta);
                for (int i = 0; i < kGrid; ++i) {
                    const double phi = 2.0 * M_PI * (i + 0.5) / kGrid;
                    const glm::dvec3 h(sinTheta * std::cos(phi), sinTheta * std::sin(phi), cosTheta);
                    const double vh = glm::dot(v, h);
                    const glm::dvec3 l = 2.0 * vh * h - v;
                    if (l.z <= 0.0 || vh <= 0.0) continue;
                    const double nl = l.z;
                    const double vis = 0.5 / (nl * std::sqrt(nDotV * nDotV * (1 - a2) + a2) + nDotV * std::sqrt(nl * nl * (1 - a2) + a2));
                    // D n.h dw_h is the grid's measure; dw_l = 4 v.h dw_h.
                    const double g = vis * nl * 4.0 * vh / cosTheta, fc = std::pow(1.0 - vh, 5.0);
                    scaleA += (1.0 - fc) * g, scaleB += fc * g;
                }
            }
            scaleA /= double(kGrid) * kGrid, scaleB /= double(kGrid) * kGrid;
            const glm::vec2 ab = EnvironmentLight::dfg(float(nDotV), float(roughness));
            const double error = std::max(std::fabs(ab.x - scaleA), std::fabs(ab.y - scaleB));
            (nDotV < 0.1 ? worstGrazing : worst) = std::max(nDotV < 0.1 ? worstGrazing : worst, error);
        }
    EXPECT_LE(worst, 5e-3);
    EXPECT_LE(worstGrazing, 1e-2);
}

// The dominant light I max(0, n.d) and the irradiance less its bands 0 to 2 together give the
// whole environment's irradiance but for the clamped cosine's bands from 4 on: max(0, x) less
// 1/4 + x/2 + 5/16 P2(x) is at most 3/32 in size (at x = 0).
TEST(EnvironmentLight, TheDominantLightAndTheRestGiveTheWholeIrradiance) {
    for (const EnvironmentLight& e : {environmentOf(smoothSky, 256), EnvironmentLight::neutral()}) {
        const glm::vec3 i = e.dominantIntensity, d = e.dominantDirection;
        EXPECT_GT(i.g, 0.1f);
        EXPECT_NEAR(glm::length(d), 1.0f, 1e-6f);
        std::mt19937 rng(17);
        for (int k = 0; k < 500; ++k) {
            const glm::vec3 n(randomUnit(rng));
            const glm::vec3 whole = e.irradiance(n);
            const glm::vec3 parts = EnvironmentLight::irradianceAt(e.shIrradianceLessDominant, n.x, n.y, n.z) +
                                    i * std::max(0.0f, glm::dot(n, d));
            for (int c = 0; c < 3; ++c) ASSERT_NEAR(parts[c], whole[c], 3.0f / 32.0f * i[c] + 1e-5f) << k;
        }
        // The light comes from where the environment is brightest: its irradiance is larger
        // facing d than facing away.
        EXPECT_GT(e.irradiance(d).g, e.irradiance(-d).g);
    }
}

TEST(EnvironmentLight, PreparedTheSameBitsAtAnyThreadCount) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(0.0f, 4.0f);
    std::vector<float> rgb(size_t(600 * 300 * 3));
    for (float& x : rgb) x = u(rng) * u(rng) * u(rng);  // a noisy map: bright texels, subnormal ones
    std::optional<EnvironmentLight> first;
    for (const ThreadCount count : kThreadCounts) {
        const ThreadCountScope scope(count);
        EnvironmentLight e = EnvironmentLight::fromEquirectangular(600, 300, rgb.data());
        if (count.exact) {
            EXPECT_EQ(scope.ran(), count.threads);
        }
        if (!first) {
            first.emplace(std::move(e));
            continue;
        }
        const std::vector<float>& a = first->levelTexels(), &b = e.levelTexels();
        ASSERT_EQ(a.size(), b.size());
        size_t differing = 0, firstDifference = a.size();
        for (size_t i = 0; i < a.size(); ++i)
            if (std::memcmp(&a[i], &b[i], sizeof(float)) != 0) differing += 1, firstDifference = std::min(firstDifference, i);
        EXPECT_EQ(differing, 0u) << count.threads << " threads; the first at float " << firstDifference << ": "
                                 << (differing ? a[firstDifference] : 0.0f) << " against " << (differing ? b[firstDifference] : 0.0f);
        for (int k = 0; k < 9; ++k) EXPECT_EQ(first->shIrradiance[k], e.shIrradiance[k]) << k;
    }
}

TEST(EnvironmentLight, BadTexelsCountAsBlack) {
    std::vector<float> rgb(size_t(64 * 32 * 3), 1.0f);
    rgb[0] = NAN, rgb[4] = INFINITY, rgb[8] = -5.0f;
    const EnvironmentLight e = EnvironmentLight::fromEquirectangular(64, 32, rgb.data());
    for (float x : e.levelTexels()) ASSERT_TRUE(std::isfinite(x) && x >= 0.0f);
    for (int k = 0; k < 9; ++k)
        for (int c = 0; c < 3; ++c) ASSERT_TRUE(std::isfinite(e.shIrradiance[k][c]));
}

TEST(EnvironmentLight, TheNeutralStudioIsLitFromAboveAndInFront) {
    const EnvironmentLight e = EnvironmentLight::neutral();
    const glm::vec3 towardsCamera(0.470f, 0.342f, 0.814f);  // azimuth 30, elevation 20 (scene::frameBounds)
    const glm::vec3 camera = e.irradiance(towardsCamera);
    const glm::vec3 key = e.irradiance(glm::normalize(glm::vec3(-0.55f, 0.65f, 0.55f)));
    const glm::vec3 up = e.irradiance({0, 1, 0}), down = e.irradiance({0, -1, 0}), back = e.irradiance({0, 0, -1});
    // A white surface facing the default camera shows about display white (the default key
    // light and ambient give 0.97 facing the light); facing the key more, the floor much less.
    EXPECT_GT(camera.g, 0.9f);
    EXPECT_LT(camera.g, 1.15f);
    EXPECT_GT(key.g, camera.g);
    EXPECT_GT(up.g, down.g * 2.0f);
    EXPECT_GT(key.g, back.g * 1.5f);
    EXPECT_EQ(key.r, key.g);  // neutral: grey light
    EXPECT_EQ(key.b, key.g);
    EXPECT_GT(e.dominantDirection.y, 0.3f);
    EXPECT_GT(e.dominantDirection.z, 0.0f);
    EXPECT_LT(e.dominantDirection.x, 0.0f);
}

// --- The shade stage ------------------------------------------------------------------------

constexpr int kSize = 16;

/// A window-space quad over the frame, normal towards the viewer (-z), camera above its centre.
raster::DrawCall quad(raster::ShadingModel model, const std::vector<glm::vec3>& normals) {
    static const std::vector<glm::vec3> positions = {{0, 0, 0.5f}, {0, kSize, 0.5f}, {kSize, kSize, 0.5f},
                                                     {0, 0, 0.5f}, {kSize, kSize, 0.5f}, {kSize, 0, 0.5f}};
    raster::DrawCall d;
    d.space = raster::PositionSpace::Window;
    d.positions = positions;
    d.normals = normals;
    d.state.shading = model;
    d.state.cull = raster::CullMode::None;
    d.state.cameraPosition = glm::vec3(8.0f, 8.0f, -20.0f);
    return d;
}

ResolvedDraw shade(const raster::DrawCall& d) { return renderResolved(d, kSize, kSize); }

const std::vector<glm::vec3> kFacingViewer(6, glm::vec3(0, 0, -1));

// Every pixel of a metallic-roughness quad under a smooth environment against the split sum
// written out in double from the prepared environment's own parts: E(n), S(r) and the table.
// Agreement to float rounding (1e-5) shows the shader composes them as the header says.
TEST(EnvironmentLighting, MetallicRoughnessPixelsAreTheSplitSumOfTheirInputs) {
    const EnvironmentLight e = environmentOf(smoothSky, 256);
    for (const auto& [metallic, roughness] : {std::pair{0.0f, 0.5f}, {1.0f, 0.3f}, {0.4f, 0.9f}}) {
        raster::DrawCall d = quad(raster::ShadingModel::MetallicRoughness, kFacingViewer);
        d.state.constantColor = glm::vec4(0.8f, 0.5f, 0.2f, 1.0f);
        d.state.metallic = metallic;
        d.state.roughness = roughness;
        d.state.lighting.environment = &e;
        const ResolvedDraw s = shade(d);
        EXPECT_EQ(s.counters.environmentPixels, s.counters.pixelsShaded);
        const glm::dvec3 albedo(0.8, 0.5, 0.2), n(0, 0, -1);
        const glm::dvec3 diffuse = albedo * (1.0 - metallic), f0 = glm::mix(glm::dvec3(0.04), albedo, double(metallic));
        for (int y = 0; y < kSize; ++y)
            for (int x = 0; x < kSize; ++x) {
                const glm::dvec3 v = glm::normalize(glm::dvec3(8, 8, -20) - glm::dvec3(x + 0.5, y + 0.5, 0.5));
                const glm::dvec3 r = 2.0 * glm::dot(n, v) * n - v;
                const glm::dvec3 irradiance(e.irradiance(glm::vec3(n)));
                const glm::dvec3 specular(e.specular(glm::vec3(r), roughness));
                const glm::dvec2 ab(EnvironmentLight::dfg(float(glm::dot(n, v)), roughness));
                const glm::dvec3 expected = diffuse * irradiance + specular * (f0 * ab.x + ab.y);
                const float* p = s.image.pixel(x, y);
                for (int c = 0; c < 3; ++c)
                    ASSERT_NEAR(p[c], expected[c], 1e-5 * std::max(1.0, expected[c])) << metallic << " " << roughness << " at " << x << "," << y;
            }
    }
}

// A white Lambertian quad under a constant environment c shows c (the environment's units are
// the ambient term's), and a rough white dielectric a little more (its specular albedo).
TEST(EnvironmentLighting, AConstantEnvironmentShowsOnWhiteSurfacesAsItsRadiance) {
    const EnvironmentLight e = environmentOf([](const glm::dvec3&) { return glm::dvec3(0.25, 0.5, 1.0); }, 128);
    raster::DrawCall d = quad(raster::ShadingModel::Lambert, kFacingViewer);
    d.state.lighting.environment = &e;
    const ResolvedDraw lambert = shade(d);
    EXPECT_EQ(lambert.counters.environmentPixels, lambert.counters.pixelsShaded);
    EXPECT_EQ(lambert.counters.pixelsShaded, uint64_t(kSize * kSize));
    for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize; ++x) {
            const float* p = lambert.image.pixel(x, y);
            // As in AConstantEnvironmentLightsAsAnAmbientTermOfItsRadiance; 64 rows: measured 6.3e-5.
            ASSERT_NEAR(p[0], 0.25f, 0.25f * 8e-5f);
            ASSERT_NEAR(p[1], 0.5f, 0.5f * 8e-5f);
            ASSERT_NEAR(p[2], 1.0f, 1.0f * 8e-5f);
        }
}

TEST(EnvironmentLighting, ADrawWithoutAnEnvironmentNeverEvaluatesOne) {
    for (raster::ShadingModel model : {raster::ShadingModel::Lambert, raster::ShadingModel::MetallicRoughness}) {
        raster::DrawCall d = quad(model, kFacingViewer);
        d.state.lighting.ambient = glm::vec3(0.2f);
        const ResolvedDraw s = shade(d);
        EXPECT_GT(s.counters.pixelsShaded, 0u);
        EXPECT_EQ(s.counters.environmentPixels, 0u);
    }
}

// The environment's lookups run in the shade stage's copy for each instruction set; the
// built-in demo scene (Lambert, metallic-roughness with textures, normals all round) must give
// the same bits on each, and at any thread count.
TEST(EnvironmentLighting, SameImageOnEveryInstructionSetAndThreadCount) {
    const std::string initial = raster::activeInstructionSet();
    auto renderDemo = [](int threads) {
        apps::RenderOptions o;
        o.scene = "demo";
        o.width = 200;
        o.height = 120;
        o.threads = threads;
        o.environment = "neutral";
        return apps::renderScene(o);
    };
    raster::useInstructionSet("baseline");
    const apps::RenderResult baseline = renderDemo(0);
    EXPECT_GT(baseline.stats.counters.environmentPixels, 0u);
    for (const std::string& set : raster::availableInstructionSets()) {
        raster::useInstructionSet(set);
        for (int threads : {1, 2}) EXPECT_EQ(renderDemo(threads).image.rgba, baseline.image.rgba) << set << ", " << threads << " threads";
    }
    raster::useInstructionSet(initial);
}

}  // namespace
}  // namespace cuberille::testing
