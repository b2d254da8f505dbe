#include "apps/explain_command.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "apps/atomic_file.h"
#include "apps/image_io.h"
#include "raster/fine.h"
#include "raster/limits.h"
#include "raster/pipeline.h"
#include "raster/sample_pattern.h"
#include "raster/setup.h"
#include "scene/input_error.h"
#include "scene/file_names.h"

namespace cuberille::apps {
namespace {

// ---- what each stage is drawn from ----------------------------------------------------------

constexpr int kSampleCounts[] = {1, 2, 4, 8, 16};
constexpr int kMaxShownPixels = 96;  // a side of the region shown

/// The framebuffer pixels a picture shows, [x0, x1) x [y0, y1).
struct Region {
    int x0, y0, x1, y1;
};

/// The pipeline run at N samples: the framebuffer after the frame (and its block classes).
struct Run {
    raster::Pipeline pipeline;
    const raster::Framebuffer& fb() const { return pipeline.framebuffer(); }

    /// The colour stored in sample s of pixel (x, y); the clear colour in tiles never touched.
    glm::vec4 sample(int x, int y, int s) const {
        const raster::Framebuffer& f = fb();
        const int tile = (y / raster::kTileSizePixels) * f.tilesX() + x / raster::kTileSizePixels;
        if (!f.tileTouched(tile)) return glm::vec4(0.0f);
        const int inTile = (y % raster::kTileSizePixels) * raster::kTileSizePixels + x % raster::kTileSizePixels;
        return f.tileColor(tile)[size_t(inTile) * f.samples() + s];
    }
};

void render(Run& run, const scene::TriScene& s, int width, int height, int samples, bool coverageOnly,
            std::vector<glm::vec4>& ones) {
    raster::FramebufferDesc desc;
    desc.widthPixels = width;
    desc.heightPixels = height;
    desc.samples = samples;
    desc.recordBlockClasses = true;
    run.pipeline.beginFrame(desc);
    raster::DrawCall d = s.drawCall();
    if (coverageOnly) {  // every triangle the same value: a sample is covered or not
        ones.assign(s.triangleCount(), glm::vec4(1.0f));
        d.triangleColors = ones;
    }
    run.pipeline.draw(d);
    run.pipeline.endFrame();
}

glm::vec2 snapped(const glm::vec3& p) {
    return {float(raster::snapToSubpixels(p.x)) / raster::kSubpixelsPerPixel,
            float(raster::snapToSubpixels(p.y)) / raster::kSubpixelsPerPixel};
}

/// Where sample k of pixel (x, y) lies, in pixels (the pattern's offsets are in 1/16 pixel).
glm::vec2 samplePoint(const raster::SamplePattern& sp, int x, int y, int k) {
    return {float(x) + 0.5f + float(sp.dx[size_t(k)]) / 16.0f, float(y) + 0.5f + float(sp.dy[size_t(k)]) / 16.0f};
}

/// Set-up of one triangle exactly as the pipeline does it (window space, no culling).
bool setUp(const scene::TriScene& s, size_t triangle, int width, int height, raster::TriangleSetup& out) {
    const raster::SetupContext context = raster::SetupContext::forDraw(
        raster::PositionSpace::Window, width, height, raster::standardSamplePattern(1), raster::CullMode::None, 0);
    raster::WindowVertex v[3];
    for (int c = 0; c < 3; ++c) {
        const glm::vec3 p = s.positions[3 * triangle + c];
        v[c] = {raster::snapToSubpixels(p.x), raster::snapToSubpixels(p.y), 0.0f, 1.0f};
    }
    int order[3];
    return raster::setupTriangle(v[0], v[1], v[2], context, out, order) == raster::SetupResult::Accepted;
}

// ---- drawing on a magnified view ------------------------------------------------------------

namespace ink {
const glm::vec3 paper{0.93f}, grid{0.6f}, centre{0.25f}, edge{0.02f}, vertex{0.9f, 0.3f, 0.0f}, bounds{1.0f, 0.55f, 0.0f};
const glm::vec3 block{0.15f, 0.3f, 0.9f}, tile{0.85f, 0.1f, 0.1f}, covered{0.1f, 0.2f, 0.8f}, uncovered{0.45f};
const glm::vec3 partial{1.0f, 0.72f, 0.35f}, full{0.5f, 0.85f, 0.5f}, both{0.95f, 0.9f, 0.35f}, inside{0.75f, 0.95f, 0.75f};
const glm::vec3 edgeColor[3] = {{0.85f, 0.15f, 0.15f}, {0.1f, 0.6f, 0.1f}, {0.15f, 0.25f, 0.9f}};
}  // namespace ink

class Magnifier {
public:
    Magnifier(const Region& r, int scale) : r_(r), scale_(scale) {
        image.width = (r.x1 - r.x0) * scale + 1;
        image.height = (r.y1 - r.y0) * scale + 1;
        image.rgba.assign(size_t(image.width) * image.height * 4, 1.0f);
        fill(0, 0, image.width, image.height, ink::paper);
    }

    /// Framebuffer coordinates (pixels, continuous) to image coordinates.
    glm::vec2 at(const glm::vec2& p) const { return {(p.x - float(r_.x0)) * float(scale_), (p.y - float(r_.y0)) * float(scale_)}; }

    void fillPixel(int x, int y, const glm::vec3& c) {
        const glm::vec2 a = at({float(x), float(y)});
        fill(int(a.x), int(a.y), int(a.x) + scale_, int(a.y) + scale_, c);
    }

    /// Pixel boundaries thin and grey, 8x8 coarse blocks blue, 64x64 tiles red.
    void grid() {
        for (int x = r_.x0; x <= r_.x1; ++x) verticalLine(x, x % 64 == 0 ? ink::tile : x % 8 == 0 ? ink::block : ink::grid, x % 8 == 0 ? 2 : 1);
        for (int y = r_.y0; y <= r_.y1; ++y) horizontalLine(y, y % 64 == 0 ? ink::tile : y % 8 == 0 ? ink::block : ink::grid, y % 8 == 0 ? 2 : 1);
    }

    void pixelCentres() {
        for (int y = r_.y0; y < r_.y1; ++y)
            for (int x = r_.x0; x < r_.x1; ++x) dot({float(x) + 0.5f, float(y) + 0.5f}, 1.5f, ink::centre, true);
    }

    void dot(const glm::vec2& p, float radius, const glm::vec3& c, bool filled) {
        const glm::vec2 q = at(p);
        for (int y = int(std::floor(q.y - radius)); y <= int(std::ceil(q.y + radius)); ++y)
            for (int x = int(std::floor(q.x - radius)); x <= int(std::ceil(q.x + radius)); ++x) {
                const float d = std::sqrt((float(x) - q.x) * (float(x) - q.x) + (float(y) - q.y) * (float(y) - q.y));
                if (d <= radius && (filled || d >= radius - 1.5f)) plot(x, y, c);
            }
    }

    void line(const glm::vec2& a, const glm::vec2& b, const glm::vec3& c, float width) {
        const glm::vec2 p = at(a), q = at(b);
        const int steps = std::max(1, int(std::ceil(2.0f * glm::length(q - p))));
        for (int i = 0; i <= steps; ++i) {
            const glm::vec2 m = p + (q - p) * (float(i) / float(steps));
            for (int y = int(std::floor(m.y - width / 2)); y <= int(std::floor(m.y + width / 2)); ++y)
                for (int x = int(std::floor(m.x - width / 2)); x <= int(std::floor(m.x + width / 2)); ++x) plot(x, y, c);
        }
    }

    /// An outline around framebuffer pixels [x0, x1) x [y0, y1).
    void outline(int x0, int y0, int x1, int y1, const glm::vec3& c, float width) {
        const glm::vec2 a{float(x0), float(y0)}, b{float(x1), float(y0)}, d{float(x1), float(y1)}, e{float(x0), float(y1)};
        line(a, b, c, width), line(b, d, c, width), line(d, e, c, width), line(e, a, c, width);
    }

    raster::Image image;

private:
    void plot(int x, int y, const glm::vec3& c) {
        if (x < 0 || y < 0 || x >= image.width || y >= image.height) return;
        float* p = image.pixel(x, y);
        p[0] = c.r, p[1] = c.g, p[2] = c.b, p[3] = 1.0f;
    }
    void fill(int x0, int y0, int x1, int y1, const glm::vec3& c) {
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) plot(x, y, c);
    }
    void verticalLine(int x, const glm::vec3& c, int width) {
        const int cx = int(at({float(x), 0.0f}).x);
        fill(cx - (width - 1) / 2, 0, cx + width / 2 + 1, image.height, c);
    }
    void horizontalLine(int y, const glm::vec3& c, int width) {
        const int cy = int(at({0.0f, float(y)}).y);
        fill(0, cy - (width - 1) / 2, image.width, cy + width / 2 + 1, c);
    }

    Region r_;
    int scale_;
};

void triangleEdges(Magnifier& m, const scene::TriScene& s, size_t t, const glm::vec3& c) {
    for (int e = 0; e < 3; ++e) m.line(snapped(s.positions[3 * t + e]), snapped(s.positions[3 * t + (e + 1) % 3]), c, 2.0f);
}

void allEdges(Magnifier& m, const scene::TriScene& s) {
    for (size_t t = 0; t < s.triangleCount(); ++t) triangleEdges(m, s, t, ink::edge);
}

// ---- the stages ---------------------------------------------------------------------------

/// 1: set-up. Snapped vertices (squares), the edges between them, the pixel bounds set-up
/// computed for the triangle (orange), over the pixel grid and centres.
raster::Image setupStage(const scene::TriScene& s, const Region& r, const ExplainOptions& o, int width, int height) {
    Magnifier m(r, o.scale);
    m.grid();
    m.pixelCentres();
    raster::TriangleSetup t;
    if (setUp(s, size_t(o.triangleIndex), width, height, t))
        m.outline(t.pixelMinX, t.pixelMinY, t.pixelMaxX + 1, t.pixelMaxY + 1, ink::bounds, 3.0f);
    allEdges(m, s);
    for (const glm::vec3& p : s.positions) m.dot(snapped(p), 4.0f, ink::vertex, true);
    return std::move(m.image);
}

/// 2: coarse. Each 8x8 block as the coarse stage classified it: partial (orange: the fine stage
/// runs), full (green: every sample covered, no per-sample test), both (yellow: different
/// triangles), untouched (paper).
raster::Image coarseStage(const scene::TriScene& s, const Region& r, const ExplainOptions& o, const Run& run) {
    Magnifier m(r, o.scale);
    const raster::Framebuffer& fb = run.fb();
    for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x) {
            const size_t b = size_t(y / raster::kBlockSizePixels) * fb.blocksX() + x / raster::kBlockSizePixels;
            const bool partial = fb.blockPartial()[b] > 0, full = fb.blockFull()[b] > 0;
            if (partial || full) m.fillPixel(x, y, partial && full ? ink::both : full ? ink::full : ink::partial);
        }
    m.grid();
    allEdges(m, s);
    return std::move(m.image);
}

/// 3: edge functions. Each pixel centre coloured by the signs of the chosen triangle's three
/// biased edge values: inside all three (green), or tinted by the edge it is outside of. The row
/// whose values go to the CSV is outlined.
raster::Image edgeStage(const scene::TriScene& s, const Region& r, const ExplainOptions& o, int width, int height,
                        int row, std::string& csv) {
    Magnifier m(r, o.scale);
    raster::TriangleSetup t;
    const bool accepted = setUp(s, size_t(o.triangleIndex), width, height, t);
    std::ostringstream out;
    out << "x,y,E0,E1,E2,covered\n";
    for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x) {
            int64_t e[3] = {-1, -1, -1};
            if (accepted) raster::edgesAtPixelCentre(t, x, y, e);
            const bool in = e[0] >= 0 && e[1] >= 0 && e[2] >= 0;
            glm::vec3 c = ink::inside;
            if (!in) {
                c = ink::paper;
                for (int k = 0; k < 3; ++k)
                    if (e[k] < 0) c = 0.75f * c + 0.25f * ink::edgeColor[k];
            }
            m.fillPixel(x, y, c);
            if (y == row) out << x << ',' << y << ',' << e[0] << ',' << e[1] << ',' << e[2] << ',' << int(in) << '\n';
        }
    m.grid();
    m.pixelCentres();
    for (int k = 0; k < 3; ++k)  // edge k lies opposite vertex k: between vertices k+1 and k+2
        m.line(snapped(s.positions[3 * size_t(o.triangleIndex) + (k + 1) % 3]),
               snapped(s.positions[3 * size_t(o.triangleIndex) + (k + 2) % 3]), ink::edgeColor[k], 2.0f);
    if (row >= r.y0 && row < r.y1) m.outline(r.x0, row, r.x1, row + 1, ink::edge, 2.0f);
    csv = out.str();
    return std::move(m.image);
}

/// 4: coverage at N samples, read back from the framebuffer: each sample point at its standard
/// position, filled where the pipeline covered it.
raster::Image coverageStage(const scene::TriScene& s, const Region& r, const ExplainOptions& o, const Run& run, int n) {
    Magnifier m(r, o.scale);
    m.grid();
    const raster::SamplePattern& sp = raster::standardSamplePattern(n);
    for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x)
            for (int k = 0; k < n; ++k) {
                const bool hit = run.sample(x, y, k).r > 0.0f;
                m.dot(samplePoint(sp, x, y, k), hit ? 3.0f : 2.5f, hit ? ink::covered : ink::uncovered, hit);
            }
    allEdges(m, s);
    return std::move(m.image);
}

/// 5: shading and output merge. Every sample dot in the colour stored for it (later triangles
/// overwrite earlier ones: .tri draws have no depth test).
raster::Image shadedStage(const scene::TriScene& s, const Region& r, const ExplainOptions& o, const Run& run, int n) {
    Magnifier m(r, o.scale);
    for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x) m.fillPixel(x, y, glm::vec3(0.0f));
    m.grid();
    const raster::SamplePattern& sp = raster::standardSamplePattern(n);
    for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x)
            for (int k = 0; k < n; ++k) {
                m.dot(samplePoint(sp, x, y, k), 2.5f, glm::vec3(run.sample(x, y, k)), true);
            }
    allEdges(m, s);
    return std::move(m.image);
}

/// 6: resolve. Each pixel the box average of its samples: k of N samples at v give k v / N.
raster::Image resolveStage(const scene::TriScene& s, const Region& r, const ExplainOptions& o, const Run& run) {
    Magnifier m(r, o.scale);
    raster::Image resolved;
    raster::resolveColor(run.fb(), resolved);
    for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x) m.fillPixel(x, y, glm::vec3(resolved.pixel(x, y)[0], resolved.pixel(x, y)[1], resolved.pixel(x, y)[2]));
    allEdges(m, s);
    return std::move(m.image);
}

scene::TriScene sceneFor(const ExplainOptions& o) {
    if (!o.scene.empty() && !o.triangle.empty()) throw scene::InputError("explain: give a .tri scene or --triangle, not both");
    if (!o.scene.empty()) {
        if (scene::fileKindOf(o.scene) != scene::FileKind::TriangleList) throw scene::InputError("explain: '" + o.scene + "' is not a .tri scene");
        return scene::loadTriScene(o.scene);
    }
    if (o.triangle.empty()) throw scene::InputError("explain: give a .tri scene or --triangle \"x0 y0 x1 y1 x2 y2\"");
    std::istringstream words(o.triangle);
    int numbers = 0;
    for (std::string word; words >> word;) ++numbers;
    if (numbers != 6)
        throw scene::InputError("--triangle: expected 6 numbers (x0 y0 x1 y1 x2 y2), found " + std::to_string(numbers));
    return scene::parseTriScene(o.triangle + " 1\n", "--triangle");
}

}  // namespace

ExplainResult explainScene(const scene::TriScene& s, const ExplainOptions& o) {
    using scene::InputError;
    if (s.triangleCount() == 0) throw InputError("explain: the scene has no triangles");
    if (o.triangleIndex < 0 || size_t(o.triangleIndex) >= s.triangleCount())
        throw InputError("--triangle-index: " + std::to_string(o.triangleIndex) + " is not a triangle of the scene (0.." +
                         std::to_string(s.triangleCount() - 1) + ")");
    if (o.scale < 4 || o.scale > 64) throw InputError("--scale: must be 4 to 64 image pixels per pixel");
    // The region: the triangles' snapped bounds and a pixel around them, inside the framebuffer.
    glm::vec2 lo(1e30f), hi(-1e30f);
    for (const glm::vec3& p : s.positions) lo = glm::min(lo, snapped(p)), hi = glm::max(hi, snapped(p));
    const int width = o.width > 0 ? o.width : std::clamp(int(std::ceil(hi.x)) + 2, 1, raster::kMaxFramebufferPixels);
    const int height = o.height > 0 ? o.height : std::clamp(int(std::ceil(hi.y)) + 2, 1, raster::kMaxFramebufferPixels);
    if (width > raster::kMaxFramebufferPixels || height > raster::kMaxFramebufferPixels)
        throw InputError("--width/--height: at most " + std::to_string(raster::kMaxFramebufferPixels));
    Region r{std::clamp(int(std::floor(lo.x)) - 1, 0, width - 1), std::clamp(int(std::floor(lo.y)) - 1, 0, height - 1),
             std::clamp(int(std::ceil(hi.x)) + 1, 1, width), std::clamp(int(std::ceil(hi.y)) + 1, 1, height)};
    if (r.x1 <= r.x0 || r.y1 <= r.y0) throw InputError("explain: the triangles lie outside the framebuffer");
    if (r.x1 - r.x0 > kMaxShownPixels || r.y1 - r.y0 > kMaxShownPixels)
        throw InputError("explain: the triangles span " + std::to_string(r.x1 - r.x0) + "x" + std::to_string(r.y1 - r.y0) +
                         " pixels; at most " + std::to_string(kMaxShownPixels) + " a side can be shown magnified");
    const size_t t = size_t(o.triangleIndex);
    const float midY = (std::min({s.positions[3 * t].y, s.positions[3 * t + 1].y, s.positions[3 * t + 2].y}) +
                        std::max({s.positions[3 * t].y, s.positions[3 * t + 1].y, s.positions[3 * t + 2].y})) / 2.0f;
    const int row = o.row >= 0 ? o.row : std::clamp(int(std::floor(midY)), r.y0, r.y1 - 1);

    ExplainResult out;
    std::vector<glm::vec4> ones;
    Run one;
    render(one, s, width, height, 1, false, ones);
    out.images.emplace_back("1-setup", setupStage(s, r, o, width, height));
    out.images.emplace_back("2-coarse", coarseStage(s, r, o, one));
    out.images.emplace_back("3-edges", edgeStage(s, r, o, width, height, row, out.edgeCsv));
    for (const int n : kSampleCounts) {
        Run coverage;
        render(coverage, s, width, height, n, true, ones);
        out.images.emplace_back("4-coverage-" + std::to_string(n), coverageStage(s, r, o, coverage, n));
    }
    for (const int n : {1, 4, 16}) {
        Run shaded;
        render(shaded, s, width, height, n, false, ones);
        if (n == 16) out.images.emplace_back("5-shaded", shadedStage(s, r, o, shaded, n));
        out.images.emplace_back("6-resolve-" + std::to_string(n), resolveStage(s, r, o, shaded));
    }
    return out;
}

int runExplainCommand(const ExplainOptions& o) {
    if (o.outDir.empty()) throw scene::InputError("--out-dir: a directory for the stage images is required");
    const ExplainResult result = explainScene(sceneFor(o), o);
    std::filesystem::create_directories(o.outDir);
    for (const auto& [name, image] : result.images) writeImageAtomically(o.outDir / (name + ".png"), image);
    AtomicOutputFile csv(o.outDir / "3-edges.csv");
    csv.stream() << result.edgeCsv;
    csv.commit();
    if (!o.quiet)
        std::printf("wrote %zu stage images and 3-edges.csv to %s\n", result.images.size(), o.outDir.c_str());
    return 0;
}

}  // namespace cuberille::apps
