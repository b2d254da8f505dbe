// The real scans in ../shared/data load and render without error. Skipped, with a message,
// when the folder is absent (a fresh clone outside the workplace).

#include <gtest/gtest.h>

#include <filesystem>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <sstream>

#include "apps/image_io.h"
#include "apps/render_command.h"
#include "scene/model_scene.h"

namespace cuberille::testing {
namespace {

namespace fs = std::filesystem;

TEST(RealData, EveryScanLoadsAndRenders) {
    const fs::path scans = fs::path(CUBERILLE_SOURCE_DIR) / ".." / "shared" / "data" / "scans";
    if (!fs::exists(scans)) GTEST_SKIP() << scans << " is absent; real-data checks skipped";
    int rendered = 0;
    for (const auto& entry : fs::recursive_directory_iterator(scans)) {
        const std::string name = entry.path().filename().string();
        if (!(name.ends_with(".ply") || name.ends_with(".ply.gz") || name.ends_with(".obj"))) continue;
        apps::RenderOptions o;
        o.scene = entry.path().string();
        o.width = 96;
        o.height = 64;
        o.quiet = true;
        const apps::RenderResult r = apps::renderScene(o);
        EXPECT_GT(r.sceneTriangles, 1000u) << name;
        EXPECT_GT(r.stats.counters.samplesPassed, 500u) << name << " should fill part of the frame";
        ++rendered;
    }
    EXPECT_GE(rendered, 3);
}

// The Asset Generator's primitive-mode models of points and lines: Cuberille draws triangles
// only, so rendering them is refused with exit code 2 (docs/cli.md). Every other model must draw.
bool pointsAndLinesByDesign(const std::string& fileName) {
    static const char* const kNames[] = {"Mesh_PrimitiveMode_00.gltf", "Mesh_PrimitiveMode_01.gltf",
                                         "Mesh_PrimitiveMode_02.gltf", "Mesh_PrimitiveMode_03.gltf",
                                         "Mesh_PrimitiveMode_07.gltf", "Mesh_PrimitiveMode_08.gltf",
                                         "Mesh_PrimitiveMode_09.gltf", "Mesh_PrimitiveMode_10.gltf"};
    return std::find(std::begin(kNames), std::end(kNames), fileName) != std::end(kNames);
}

TEST(RealData, EveryGltfSampleLoadsAndRenders) {
    const fs::path data = fs::path(CUBERILLE_SOURCE_DIR) / ".." / "shared" / "data";
    if (!fs::exists(data / "gltf")) GTEST_SKIP() << data << " is absent; real-data checks skipped";
    int rendered = 0;
    for (const char* folder : {"gltf", "asset-generator"}) {
        for (const auto& entry : fs::recursive_directory_iterator(data / folder)) {
            const std::string name = entry.path().filename().string();
            if (!(name.ends_with(".gltf") || name.ends_with(".glb"))) continue;
            apps::RenderOptions o;
            o.scene = entry.path().string();
            o.width = 64;
            o.height = 48;
            o.quiet = true;
            if (pointsAndLinesByDesign(name)) {
                try {
                    apps::renderScene(o);
                    ADD_FAILURE() << name << ": rendered a model of points and lines";
                } catch (const std::exception& e) {
                    EXPECT_NE(std::string(e.what()).find("no triangles to draw"), std::string::npos) << e.what();
                }
                ++rendered;
                continue;
            }
            try {
                const apps::RenderResult r = apps::renderScene(o);
                EXPECT_GT(r.sceneTriangles, 0u) << name;
                // Material_AlphaMask_03 masks with alphaCutoff 1.1: by design nothing survives.
                if (name == "Material_AlphaMask_03.gltf") {
                    EXPECT_EQ(r.stats.counters.samplesPassed, 0u) << name;
                } else {
                    EXPECT_GT(r.stats.counters.samplesPassed, 0u) << name << " drew nothing";
                }
            } catch (const std::exception& e) {
                ADD_FAILURE() << name << ": " << e.what();
            }
            ++rendered;
        }
    }
    EXPECT_GE(rendered, 15);
}

// --- The glTF Asset Generator models against their sample images ---------------------------
//
// The sample images come from a web viewer with image-based lighting and an environment
// backdrop, so pixels cannot match; what must match is structure: where the model is, which
// texels land where, what is cut out or blended. The metric (docs/asset-generator-report.md):
// 1. Render the model at 256x256 from the front (azimuth 0, elevation 0, the viewer's view),
//    and crop our image to the model's projected bounds; crop the sample image to the centred
//    rectangle of the same aspect whose longer side spans 90% of it (the viewer's framing).
// 2. Average both crops over a 12x12 grid of cells, in linear RGB. Only cells our model covers
//    wholly count (no pixel of our background in them): through cut-outs and blends the
//    viewer's environment shows, which no renderer without it can match.
// 3. Structure: the Pearson correlation of those cells' luminance. Colour: the mean distance
//    of their chromaticity (r, g) / (r + g + b).
// Verdicts: a model whose covered cells vary (luminance coefficient of variation >= 0.1 in our
// image) is plainly wrong when the correlation is below 0.3 (a flipped, missing or misplaced
// texture decorrelates; lighting differences do not); a flat one when the chroma distance is
// above 0.15. Blended models are reported, not judged (the backdrop is part of their colour),
// and so are animated ones (we pose them at time 0; the samples' pose time is not recorded).

constexpr int kGrid = 12;
/// Flat models' brightness against the sample's may differ by up to this factor either way.
/// Measured over the judged flat models: 0.26 (Material_AlphaMask_06; metals in the viewer's
/// environment light, Material_00/02/05, are 0.28) to 1.16 (Material_03). A model drawn black or
/// unlit falls far outside; 5 leaves the metals a margin of a fifth.
constexpr double kFlatBrightness = 5.0;

struct CellGrid {
    std::vector<glm::dvec3> cells = std::vector<glm::dvec3>(kGrid * kGrid, glm::dvec3(0.0));
    std::vector<bool> covered = std::vector<bool>(kGrid * kGrid, true);  // no background pixel
};

CellGrid cellsOf(const raster::Image& image, double x0, double y0, double x1, double y1,
                 const glm::vec3* background = nullptr) {
    CellGrid g;
    std::vector<int> counts(kGrid * kGrid, 0);
    for (int y = std::max(0, int(y0)); y < std::min(image.height, int(std::ceil(y1))); ++y)
        for (int x = std::max(0, int(x0)); x < std::min(image.width, int(std::ceil(x1))); ++x) {
            const int cx = std::clamp(int((x + 0.5 - x0) / (x1 - x0) * kGrid), 0, kGrid - 1);
            const int cy = std::clamp(int((y + 0.5 - y0) / (y1 - y0) * kGrid), 0, kGrid - 1);
            const float* p = image.pixel(x, y);
            g.cells[cy * kGrid + cx] += glm::dvec3(p[0], p[1], p[2]);
            ++counts[cy * kGrid + cx];
            if (background && glm::distance(glm::vec3(p[0], p[1], p[2]), *background) < 1e-4f) g.covered[cy * kGrid + cx] = false;
        }
    for (int i = 0; i < kGrid * kGrid; ++i)
        if (counts[i]) g.cells[i] /= counts[i];
    else g.covered[i] = false;
    return g;
}

struct Comparison {
    int cells = 0;             // covered cells compared
    double variation = 0.0;    // our luminance's coefficient of variation over them
    double correlation = NAN;  // NaN: a side without luminance variation
    double chromaDistance = 0.0;
    double brightnessRatio = NAN;  // our mean luminance over the sample's, on the covered cells
};

Comparison compare(const CellGrid& ours, const CellGrid& sample) {
    auto luminance = [](const glm::dvec3& c) { return 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b; };
    auto chroma = [](const glm::dvec3& c) {
        const double sum = c.r + c.g + c.b;
        return sum > 1e-6 ? glm::dvec2(c.r, c.g) / sum : glm::dvec2(1.0 / 3.0);
    };
    std::vector<int> used;
    for (int i = 0; i < kGrid * kGrid; ++i)
        if (ours.covered[i]) used.push_back(i);
    Comparison c;
    c.cells = int(used.size());
    if (used.empty()) return c;
    double ma = 0, mb = 0;
    for (int i : used) ma += luminance(ours.cells[i]) / c.cells, mb += luminance(sample.cells[i]) / c.cells;
    double sab = 0, saa = 0, sbb = 0;
    for (int i : used) {
        const double da = luminance(ours.cells[i]) - ma, db = luminance(sample.cells[i]) - mb;
        sab += da * db, saa += da * da, sbb += db * db;
        c.chromaDistance += glm::distance(chroma(ours.cells[i]), chroma(sample.cells[i])) / c.cells;
    }
    c.variation = ma > 0 ? std::sqrt(saa / c.cells) / ma : 0.0;
    if (mb > 1e-6) c.brightnessRatio = ma / mb;
    if (saa > 1e-12 && sbb > 1e-12) c.correlation = sab / std::sqrt(saa * sbb);
    return c;
}

TEST(RealData, AssetGeneratorModelsMatchTheirSampleImages) {
    const fs::path root = fs::path(CUBERILLE_SOURCE_DIR) / ".." / "shared" / "data" / "asset-generator";
    if (!fs::exists(root)) GTEST_SKIP() << root << " is absent; real-data checks skipped";
    std::vector<fs::path> models;
    for (const auto& entry : fs::recursive_directory_iterator(root))
        if (entry.path().extension() == ".gltf") models.push_back(entry.path());
    std::sort(models.begin(), models.end());
    std::ostringstream report;
    report << "| model | triangles | covered cells | variation | structure (correlation) | colour (chroma distance) | "
              "brightness (ratio) | verdict | with `--environment neutral`: structure, colour, brightness |\n"
           << "|---|---:|---:|---:|---:|---:|---:|---|---|\n";
    int compared = 0, failed = 0;
    for (const fs::path& model : models) {
        const std::string name = model.stem().string();
        const fs::path sample = model.parent_path() / "Figures" / "SampleImages" / (name + ".png");
        if (!fs::exists(sample)) continue;
        apps::RenderOptions o;
        o.scene = model.string();
        o.width = o.height = 256;
        o.msaa = 4;
        o.azimuth = 0.0f;
        o.elevation = 0.0f;
        o.quiet = true;
        std::string verdict;
        Comparison c, lit;  // lit: the same with the built-in studio environment
        apps::RenderResult r;
        if (pointsAndLinesByDesign(model.filename().string())) {
            verdict = "not compared: points and lines are not drawn (by design)";
        } else {
            r = apps::renderScene(o);
            scene::ModelSceneOptions view;
            view.azimuthDegrees = view.elevationDegrees = 0.0f;
            const scene::Scene s = scene::loadModelScene(model, view, [](const std::string&) {});
            const scene::Bounds b = scene::boundsOf(s.meshes);
            // Our crop: the projected bounds.
            const glm::mat4 clip = s.camera.clipFromWorld(1.0f);
            glm::dvec2 lo(1e9), hi(-1e9);
            for (int k = 0; k < 8; ++k) {
                const glm::vec3 corner(k & 1 ? b.max.x : b.min.x, k & 2 ? b.max.y : b.min.y, k & 4 ? b.max.z : b.min.z);
                const glm::vec4 p = clip * glm::vec4(corner, 1.0f);
                const glm::dvec2 px((p.x / p.w * 0.5 + 0.5) * o.width, (0.5 - p.y / p.w * 0.5) * o.height);
                lo = glm::min(lo, px), hi = glm::max(hi, px);
            }
            // The sample's crop: same aspect, longer side 90% of the image, centred.
            const raster::Image reference = apps::readImage(sample);
            const double aspect = (hi.x - lo.x) / std::max(1e-9, hi.y - lo.y);
            const double side = 0.9 * reference.width;
            const double w = aspect >= 1.0 ? side : side * aspect, h = aspect >= 1.0 ? side / aspect : side;
            const double cx = reference.width / 2.0, cy = reference.height / 2.0;
            const glm::vec3 background(s.background);
            const CellGrid sampleCells = cellsOf(reference, cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2);
            c = compare(cellsOf(r.image, lo.x, lo.y, hi.x, hi.y, &background), sampleCells);
            apps::RenderOptions withEnvironment = o;
            withEnvironment.environment = "neutral";
            lit = compare(cellsOf(apps::renderScene(withEnvironment).image, lo.x, lo.y, hi.x, hi.y, &background), sampleCells);
            ++compared;
            const bool structured = c.variation >= 0.1;
            // A flat model is judged on its colour and its brightness: the viewer's image-based
            // lighting and ours differ by a factor (measured over the flat models: kFlatBrightness
            // below), never by the order of magnitude of a black or a washed-out model. Both
            // lightings are judged, the default key light and the studio environment.
            auto wrongStructure = [&](const Comparison& k) { return structured && !(k.correlation >= 0.3); };
            auto wrongColour = [&](const Comparison& k) {
                return !structured && (k.chromaDistance > 0.15 ||
                                       !(k.brightnessRatio >= 1.0 / kFlatBrightness && k.brightnessRatio <= kFlatBrightness));
            };
            const bool structureWrong = wrongStructure(c) || wrongStructure(lit);
            const bool colourWrong = wrongColour(c) || wrongColour(lit);
            const bool blended = name.starts_with("Material_AlphaBlend");
            // Material_AlphaMask_03 cuts everything away (alphaCutoff 1.1) by design.
            const bool emptyByDesign = name == "Material_AlphaMask_03";
            std::ifstream file(model);
            const std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
            const bool animated = text.find("\"animations\"") != std::string::npos;
            verdict = blended             ? "reported, not judged (blended over the viewer's backdrop)"
                      : animated          ? "reported, not judged (animated: the sample's pose time is unknown)"
                      : c.cells == 0 && emptyByDesign ? "nothing covered (by design: alpha cutoff above 1)"
                      : c.cells == 0       ? "**nothing covered**"
                      : structureWrong     ? "**plainly wrong: structure**"
                      : colourWrong        ? "**plainly wrong: colour**"
                      : structured         ? "matches (structure)"
                                           : "matches (flat: colour)";
            if (!blended && !animated && c.cells > 0 && (structureWrong || colourWrong)) {
                ++failed;
                ADD_FAILURE() << name << ": correlation " << c.correlation << ", chroma distance " << c.chromaDistance
                              << ", brightness ratio " << c.brightnessRatio << "; with the environment " << lit.correlation
                              << ", " << lit.chromaDistance << ", " << lit.brightnessRatio;
            }
            if (c.cells == 0 && !emptyByDesign) {
                ++failed;
                ADD_FAILURE() << name << ": covers no whole cell of its own bounds";
            }
        }
        char line[640];
        std::snprintf(line, sizeof line, "| %s | %zu | %d | %.3f | %.3f | %.3f | %.2f | %s | %.3f, %.3f, %.2f |\n", name.c_str(),
                      r.sceneTriangles, c.cells, c.variation, c.correlation, c.chromaDistance, c.brightnessRatio,
                      verdict.c_str(), lit.correlation, lit.chromaDistance, lit.brightnessRatio);
        report << line;
    }
    // Into the build tree: a test leaves the working tree as it found it.
    const fs::path out = fs::path(CUBERILLE_BUILD_DIR) / "asset_generator_report.md";
    std::ofstream(out) << "# glTF Asset Generator: Cuberille against the sample images\n\n"
                       << compared << " models compared, " << failed << " plainly wrong.\n\n" << report.str();
    std::printf("report: %s\n", out.c_str());
    EXPECT_GE(compared, 50);
}

// --- The Khronos sample models against their screenshots ---------------------------------
//
// The same metric as the Asset Generator's, for the sample models in ../shared/data/gltf whose
// screenshot is a still image of a static model. A screenshot's camera is not recorded, so each
// model is rendered from a view chosen by eye to match it (kSampleViews), at the screenshot's
// aspect; both images are cropped to the bounding box of the pixels that differ from their own
// background (our background colour; the screenshot's top-left pixel, by more than
// kScreenshotBackgroundTolerance) rather than to projected bounds, since the viewer's framing is
// unknown too. Judged as the Asset Generator's models are (structured ones on the correlation,
// flat ones on colour and brightness) are only the test panels photographed head-on, whose view
// is not a guess; the rest are reported: the box's and the helmet's three-quarter views are
// guesses, and a lit box's structure is its lighting (the screenshot's top face is its darkest,
// ours its brightest), not its material. The animated models' screenshots are GIFs of the animation
// and are not compared (their pose is unknown, as for the Asset Generator's animated models).

/// A screenshot pixel belongs to the model where its linear RGB differs from the top-left pixel's
/// by more than this in any channel. Measured on the PNG screenshots' borders: flat to the bit but
/// for the spheres' (a gradient, within 0.014); the JPEGs' noise is not measured, and where it
/// exceeds this the crop is the whole image, which for the test panels (filling their frame) is
/// the crop anyway.
constexpr float kScreenshotBackgroundTolerance = 0.02f;

struct SampleView {
    const char* model;       // under ../shared/data/gltf
    const char* screenshot;  // under the model's folder
    float azimuthDegrees, elevationDegrees;
    const char* reportedOnly;  // why the model is reported, not judged; null: judged
};
constexpr const char* kGuessedView = "reported, not judged (the screenshot's view is guessed)";
constexpr SampleView kSampleViews[] = {
    {"Box/Box.glb", "Box/screenshot/screenshot.png", 35, 20, "reported, not judged (a flat box: its structure is the lighting)"},
    {"BoxTextured/BoxTextured.glb", "BoxTextured/screenshot/screenshot.png", 35, 20, kGuessedView},
    {"DamagedHelmet/DamagedHelmet.glb", "DamagedHelmet/screenshot/screenshot.png", 55, 10, kGuessedView},
    {"Avocado/glTF/Avocado.gltf", "Avocado/screenshot/screenshot.jpg", 0, 0, kGuessedView},
    {"MetalRoughSpheresNoTextures/glTF/MetalRoughSpheresNoTextures.gltf", "MetalRoughSpheresNoTextures/screenshot/screenshot.png", 0, 0,
     "not compared (spheres with gaps: no cell is wholly covered)"},
    {"AlphaBlendModeTest/glTF/AlphaBlendModeTest.gltf", "AlphaBlendModeTest/screenshot/screenshot.png", 0, 10,
     "reported, not judged (blended over the viewer's backdrop)"},
    {"Triangle/Triangle.gltf", "Triangle/screenshot/screenshot.png", 0, 0, nullptr},
    {"VertexColorTest/glTF/VertexColorTest.gltf", "VertexColorTest/screenshot/screenshot.png", 0, 0, nullptr},
    {"TextureTransformTest/glTF/TextureTransformTest.gltf", "TextureTransformTest/screenshot/screenshot.jpg", 0, 0, nullptr},
    {"MultiUVTest/glTF/MultiUVTest.gltf", "MultiUVTest/screenshot/screenshot.jpg", 0, 0, nullptr},
};

/// The bounding box of the pixels that differ from `background` by more than `tolerance`, as
/// (x0, y0, x1, y1) pixel edges; the whole image when none do.
glm::dvec4 modelBox(const raster::Image& image, const glm::vec3& background, float tolerance) {
    int x0 = image.width, y0 = image.height, x1 = 0, y1 = 0;
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) {
            const float* p = image.pixel(x, y);
            const glm::vec3 d = glm::abs(glm::vec3(p[0], p[1], p[2]) - background);
            if (std::max({d.r, d.g, d.b}) <= tolerance) continue;
            x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x + 1), y1 = std::max(y1, y + 1);
        }
    if (x1 <= x0) return {0, 0, image.width, image.height};
    return {x0, y0, x1, y1};
}

TEST(RealData, SampleModelsMatchTheirScreenshots) {
    const fs::path root = fs::path(CUBERILLE_SOURCE_DIR) / ".." / "shared" / "data" / "gltf";
    if (!fs::exists(root)) GTEST_SKIP() << root << " is absent; real-data checks skipped";
    std::ostringstream report;
    report << "| model | view (azimuth, elevation) | covered cells | variation | structure | colour | brightness | verdict | "
              "with `--environment neutral`: structure, colour, brightness |\n"
           << "|---|---|---:|---:|---:|---:|---:|---|---|\n";
    int compared = 0, judged = 0;
    for (const SampleView& v : kSampleViews) {
        const fs::path model = root / v.model, shot = root / v.screenshot;
        if (!fs::exists(model) || !fs::exists(shot)) continue;
        const raster::Image screenshot = apps::readImage(shot);
        apps::RenderOptions o;
        o.scene = model.string();
        const double aspect = double(screenshot.width) / screenshot.height;
        o.width = aspect >= 1.0 ? 256 : int(std::lround(256 * aspect));
        o.height = aspect >= 1.0 ? int(std::lround(256 / aspect)) : 256;
        o.msaa = 4;
        o.azimuth = v.azimuthDegrees;
        o.elevation = v.elevationDegrees;
        o.quiet = true;
        const apps::RenderResult plain = apps::renderScene(o);
        apps::RenderOptions withEnvironment = o;
        withEnvironment.environment = "neutral";
        const apps::RenderResult lit = apps::renderScene(withEnvironment);
        const scene::Scene s = scene::loadModelScene(model, {}, [](const std::string&) {});
        const glm::vec3 background(s.background);
        const float* corner = screenshot.pixel(0, 0);
        const glm::dvec4 theirs = modelBox(screenshot, glm::vec3(corner[0], corner[1], corner[2]), kScreenshotBackgroundTolerance);
        const CellGrid sampleCells = cellsOf(screenshot, theirs.x, theirs.y, theirs.z, theirs.w);
        auto judge = [&](const raster::Image& ours) {
            const glm::dvec4 box = modelBox(ours, background, 0.0f);
            return compare(cellsOf(ours, box.x, box.y, box.z, box.w, &background), sampleCells);
        };
        const Comparison c = judge(plain.image), e = judge(lit.image);
        ++compared;
        const bool structured = c.variation >= 0.1;
        auto wrong = [&](const Comparison& k) {
            return structured ? !(k.correlation >= 0.3)
                              : k.chromaDistance > 0.15 || !(k.brightnessRatio >= 1.0 / kFlatBrightness && k.brightnessRatio <= kFlatBrightness);
        };
        const std::string name = fs::path(v.model).stem().string();
        const std::string verdict = v.reportedOnly ? v.reportedOnly
                                    : c.cells == 0  ? "**nothing covered**"
                                    : wrong(c) || wrong(e) ? "**plainly wrong**"
                                    : structured    ? "matches (structure)"
                                                    : "matches (flat: colour)";
        if (!v.reportedOnly) {
            ++judged;
            EXPECT_GT(c.cells, 0) << name;
            EXPECT_FALSE(wrong(c)) << name << ": correlation " << c.correlation << ", chroma distance " << c.chromaDistance
                                   << ", brightness ratio " << c.brightnessRatio;
            EXPECT_FALSE(wrong(e)) << name << " with the environment: correlation " << e.correlation << ", chroma distance "
                                   << e.chromaDistance << ", brightness ratio " << e.brightnessRatio;
        }
        char line[640];
        std::snprintf(line, sizeof line, "| %s | %.0f°, %.0f° | %d | %.3f | %.3f | %.3f | %.2f | %s | %.3f, %.3f, %.2f |\n", name.c_str(),
                      v.azimuthDegrees, v.elevationDegrees, c.cells, c.variation, c.correlation, c.chromaDistance, c.brightnessRatio,
                      verdict.c_str(), e.correlation, e.chromaDistance, e.brightnessRatio);
        report << line;
    }
    const fs::path out = fs::path(CUBERILLE_BUILD_DIR) / "sample_models_report.md";
    std::ofstream(out) << "# Khronos sample models: Cuberille against the screenshots\n\n" << compared << " models compared.\n\n"
                       << report.str();
    std::printf("report: %s\n", out.c_str());
    EXPECT_GE(compared, 8);
    EXPECT_EQ(judged, 4);
}

}  // namespace
}  // namespace cuberille::testing
