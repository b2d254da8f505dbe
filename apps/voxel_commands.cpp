#include "apps/voxel_commands.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "raster/clock.h"
#include "apps/atomic_file.h"
#include "apps/render_options_cli.h"
#include "raster/parallel.h"
#include "scene/file_names.h"
#include "scene/input_error.h"
#include "scene/ply_loader.h"
#include "lod/pyramid_ranges.h"
#include "voxel/cvox_file.h"
#include "voxel/partial_voxelization_file.h"
#include "voxel/voxel_export.h"

namespace cuberille::apps {
namespace {

double peakResidentMib() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return double(u.ru_maxrss) / 1024.0;  // Linux reports KiB
}

void requireKind(const std::filesystem::path& p, scene::FileKind kind, const char* ext, const char* what) {
    if (scene::fileKindOf(p) != kind) throw scene::InputError(p.string() + ": " + what + " must end in " + ext);
}

void warnToStderr(const std::string& message) { std::fprintf(stderr, "cuberille: warning: %s\n", message.c_str()); }

/// "\rvoxelize: 12/40 chunks" on a terminal, at most ten times a second; nothing when piped.
std::function<void(size_t, size_t)> terminalProgress(const char* what, const char* unit, bool quiet) {
    if (quiet || !::isatty(STDERR_FILENO)) return {};
    return [what, unit, last = 0.0](size_t done, size_t total) mutable {
        const double now = raster::nowMs();
        if (done != total && now - last < 100.0) return;
        last = now;
        std::fprintf(stderr, "\r%s: %zu/%zu %s%s", what, done, total, unit, done == total ? "\n" : "");
        std::fflush(stderr);
    };
}

lod::SimplifyMethod parseSimplify(const std::string& name) {
    if (name == "parallel") return lod::SimplifyMethod::Parallel;
    if (name == "serial") return lod::SimplifyMethod::Serial;
    throw scene::InputError("--simplify " + name + ": expected parallel or serial");
}

nlohmann::json pyramidJson(const lod::PyramidStats& p) {
    return {{"levels", p.levels},
            {"blocksPerLevel", p.blocksPerLevel},
            {"voxelsPerLevel", p.voxelsPerLevel},
            {"skirtFaces", p.skirtFaces},
            {"hiddenFacesCleared", p.hiddenFacesCleared},
            {"simplifyMs", p.simplifyMs}};
}

// Every command that makes a model refuses an input without triangles: an empty output and exit
// code 0 would hide a file read wrongly (docs/cli.md, exit codes).
void requireTriangles(const voxel::MeshView& view, const std::filesystem::path& input, const char* command) {
    if (view.triangleCount() == 0)
        throw scene::InputError(input.string() + ": no triangles to " + command + " (no faces)");
}

std::string formatNumber(double v) {
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%g", v);
    return buffer;
}

void writeModelFiles(const voxel::VoxelModel& model, const std::filesystem::path& out,
                     const std::filesystem::path& exportPath, double& writeMs) {
    const double t0 = raster::nowMs();
    // Both files are complete before either is renamed into place.
    AtomicOutputFile cvox(out);
    voxel::writeCvox(model, cvox.stream());
    std::unique_ptr<AtomicOutputFile> text;
    if (!exportPath.empty()) {
        text = std::make_unique<AtomicOutputFile>(exportPath);
        voxel::writeVoxelExport(model, text->stream());
    }
    cvox.commit();
    if (text) text->commit();
    writeMs = raster::nowMs() - t0;
}

}  // namespace

voxel::Separability parseSeparability(const std::string& name) {
    if (name == "conservative") return voxel::Separability::Conservative;
    if (name == "26") return voxel::Separability::TwentySix;
    if (name == "6") return voxel::Separability::Six;
    throw scene::InputError("--separability " + name + ": expected conservative, 26 or 6");
}

int runPackCommand(const PackOptions& o) {
    requireKind(o.out, scene::FileKind::GeometryStream, ".cgs", "the geometry stream");
    requireOutputPath(o.out, "-o");
    requireOutputPath(o.statsPath, "--stats");
    if (o.chunkTriangles == 0) throw scene::InputError("--chunk-triangles must be at least 1");
    const double t0 = raster::nowMs();
    // A geometry stream is re-written with its own chunks; other files are cut at the asked size.
    const std::unique_ptr<voxel::MeshView> view = voxel::openMeshView(o.input, warnToStderr, o.chunkTriangles);
    requireTriangles(*view, o.input, "pack");
    const double loadMs = raster::nowMs() - t0;
    const double w0 = raster::nowMs();
    AtomicOutputFile out(o.out);
    const voxel::GeometryStreamWriteStats s = voxel::writeGeometryStream(*view, out.stream());
    out.commit();
    const double writeMs = raster::nowMs() - w0;
    if (!o.quiet)
        std::printf("packed %s: %llu triangles, %llu vertices in %llu chunks, %.1f MiB (LZ4 %.2fx) -> %s\n",
                    o.input.string().c_str(), (unsigned long long)s.triangles, (unsigned long long)s.vertices,
                    (unsigned long long)s.chunks, double(s.compressedBytes) / (1 << 20),
                    s.compressedBytes ? double(s.rawBytes) / double(s.compressedBytes) : 0.0, o.out.string().c_str());
    if (!o.statsPath.empty())
        writeJsonAtomically(o.statsPath, {{"input", o.input.string()},
                                          {"chunks", s.chunks},
                                          {"triangles", s.triangles},
                                          {"vertices", s.vertices},
                                          {"rawBytes", s.rawBytes},
                                          {"compressedBytes", s.compressedBytes},
                                          {"times", {{"loadMs", loadMs}, {"writeMs", writeMs}}}});
    return 0;
}

namespace {

// What every form of `voxelize` checks and sets up before any work.
struct VoxelizeSettings {
    voxel::VoxelizeOptions voxelize;
    lod::PyramidOptions pyramid;
};

VoxelizeSettings voxelizeSettings(const VoxelizeCommandOptions& o) {
    requireKind(o.out, scene::FileKind::VoxelModel, ".cvox", "the voxel model");
    requireOutputPath(o.out, "-o");
    requireOutputPath(o.exportVoxels, "--export-voxels");
    requireOutputPath(o.statsPath, "--stats");
    if (!voxel::isValidResolution(o.resolution))
        throw scene::InputError("--resolution " + std::to_string(o.resolution) + ": expected a power of two from " +
                                std::to_string(voxel::kMinResolution) + " to " + std::to_string(voxel::kMaxResolution));
    VoxelizeSettings v;
    v.voxelize.resolution = o.resolution;
    v.voxelize.separability = parseSeparability(o.separability);
    v.voxelize.keepSourceTriangles = !o.noSourceTriangles;
    v.pyramid.method = parseSimplify(o.simplify);
    v.pyramid.maxLevels = o.levels;
    return v;
}

std::unique_ptr<voxel::MeshView> openVoxelizeInput(const VoxelizeCommandOptions& o) {
    std::unique_ptr<voxel::MeshView> view = voxel::openMeshView(o.input, warnToStderr);
    requireTriangles(*view, o.input, "voxelize");
    return view;
}

// The summary and --stats: the last steps of `voxelize`, on one machine or after joining a
// distributed voxelization's ranges. `blocks`: the model's blocks at every level.
int reportVoxelize(const VoxelizeCommandOptions& o, const VoxelizeSettings& v, const voxel::VoxelizeStats& s,
                   const lod::PyramidStats& ps, size_t blocks, double openMs, double writeMs, double startMs) {
    const double totalMs = raster::nowMs() - startMs;
    if (!o.quiet)
        std::printf("voxelized %s at %u^3 (%s): %llu triangles -> %llu voxels in %llu blocks, %.0f ms "
                    "(open %.0f, rasterize %.0f, merge %.0f, emit %.0f, simplify %.0f, write %.0f); %u LOD levels, "
                    "%zu blocks in all -> %s%s\n",
                    o.input.string().c_str(), o.resolution, voxel::separabilityName(v.voxelize.separability),
                    (unsigned long long)s.triangles, (unsigned long long)s.voxels, (unsigned long long)s.blocks, totalMs,
                    openMs, s.rasterizeMs, s.mergeMs, s.emitMs, ps.simplifyMs, writeMs, ps.levels, blocks,
                    o.out.string().c_str(),
                    s.woundInwards ? " (the mesh is wound inwards: its voxels' normals and faces were turned outwards)" : "");
    if (!o.statsPath.empty()) {
        const double seconds = totalMs / 1000.0;
        writeJsonAtomically(o.statsPath,
                  {{"input", o.input.string()},
                   {"resolution", o.resolution},
                   {"separability", voxel::separabilityName(v.voxelize.separability)},
                   {"threads", raster::hardwareThreads()},
                   {"treesBuilt", s.threads},
                   {"chunks", s.chunks},
                   {"triangles", s.triangles},
                   {"leafPieces", s.leafPieces},
                   {"exactTests", s.exactTests},
                   {"conservativeVoxels", s.conservativeVoxels},
                   {"woundInwards", s.woundInwards},
                   {"voxels", s.voxels},
                   {"blocks", s.blocks},
                   {"sourceTriangles", s.sourceTriangles},
                   {"lod", pyramidJson(ps)},
                   {"octreeBytes", s.octreeBytes},
                   {"peakResidentMib", peakResidentMib()},
                   {"trianglesPerSecond", seconds > 0 ? double(s.triangles) / seconds : 0.0},
                   {"voxelsPerSecond", seconds > 0 ? double(s.voxels) / seconds : 0.0},
                   {"times",
                    {{"openMs", openMs},
                     {"readMsAllThreads", s.readMs},
                     {"rasterizeMs", s.rasterizeMs},
                     {"mergeMs", s.mergeMs},
                     {"emitMs", s.emitMs},
                     {"simplifyMs", ps.simplifyMs},
                     {"writeMs", writeMs},
                     {"totalMs", totalMs}}}});
    }
    return 0;
}

void requireVoxels(const VoxelizeCommandOptions& o, uint64_t voxels, uint64_t triangles) {
    if (voxels == 0)
        throw scene::InputError(o.input.string() + ": no voxels: its " + std::to_string(triangles) +
                                " triangles have no area at " + std::to_string(o.resolution) + "^3");
}

// The voxelized model's LOD pyramid and files, then the summary and --stats.
int finishVoxelize(const VoxelizeCommandOptions& o, const VoxelizeSettings& v, voxel::VoxelModel model,
                   const voxel::VoxelizeStats& s, double openMs, double startMs) {
    requireVoxels(o, model.voxelCount(), s.triangles);
    lod::PyramidStats ps;
    lod::buildLodPyramid(model, v.pyramid, &ps);
    double writeMs = 0;
    writeModelFiles(model, o.out, o.exportVoxels, writeMs);
    return reportVoxelize(o, v, s, ps, model.blocks.size(), openMs, writeMs, startMs);
}

lod::PyramidRangePlan planFromJson(const std::string& text) {
    const nlohmann::json j = nlohmann::json::parse(text);
    lod::PyramidRangePlan plan;
    plan.levels = j.at("levels").get<uint32_t>();
    plan.splitLevel = j.at("splitLevel").get<uint32_t>();
    plan.rangeStarts = j.at("rangeStarts").get<std::vector<uint64_t>>();
    return plan;
}

}  // namespace

int runVoxelizeCommand(const VoxelizeCommandOptions& o) {
    VoxelizeSettings v = voxelizeSettings(o);
    v.voxelize.progress = terminalProgress("voxelize", "chunks", o.quiet);
    raster::ThreadLimit threadLimit(o.threads);
    const double t0 = raster::nowMs();
    const std::unique_ptr<voxel::MeshView> view = openVoxelizeInput(o);
    const double openMs = raster::nowMs() - t0;
    voxel::VoxelizeStats s;
    voxel::VoxelModel model = voxel::voxelizeMesh(*view, v.voxelize, &s);
    return finishVoxelize(o, v, std::move(model), s, openMs, t0);
}

size_t voxelizeChunkCount(const VoxelizeCommandOptions& o) {
    voxelizeSettings(o);
    return openVoxelizeInput(o)->chunkCount();
}

void voxelizeChunkRun(const VoxelizeCommandOptions& o, size_t firstChunk, size_t chunkCount, const std::filesystem::path& part) {
    const VoxelizeSettings v = voxelizeSettings(o);
    raster::ThreadLimit threadLimit(o.threads);
    const std::unique_ptr<voxel::MeshView> view = openVoxelizeInput(o);
    if (firstChunk > view->chunkCount() || chunkCount > view->chunkCount() - firstChunk)
        throw scene::InputError(o.input.string() + ": chunks " + std::to_string(firstChunk) + " + " +
                                std::to_string(chunkCount) + " outside its " + std::to_string(view->chunkCount()));
    const voxel::PartialVoxelization p = voxel::voxelizeChunks(*view, v.voxelize, firstChunk, chunkCount);
    AtomicOutputFile out(part);
    voxel::writePartialVoxelization(p, out.stream());
    out.commit();
}

std::string planVoxelizeRanges(const VoxelizeCommandOptions& o, const std::vector<std::filesystem::path>& parts,
                               size_t wantedRanges) {
    const VoxelizeSettings v = voxelizeSettings(o);
    const std::unique_ptr<voxel::MeshView> view = openVoxelizeInput(o);
    // The parts must hold every chunk once: their runs, in order, tile [0, chunk count).
    std::vector<std::pair<uint64_t, uint64_t>> runs, blocks;
    voxel::VoxelModel header;
    for (const std::filesystem::path& path : parts) {
        const voxel::PartialVoxelizationIndex index = voxel::readPartialVoxelizationIndex(path);
        runs.push_back({index.part.firstChunk, index.part.chunkCount});
        header = index.part.header;
        blocks.insert(blocks.end(), index.blocks.begin(), index.blocks.end());
    }
    std::sort(runs.begin(), runs.end());
    uint64_t next = 0;
    for (const auto& [first, count] : runs) {
        if (first != next) break;
        next = first + count;
    }
    if (next != view->chunkCount() || runs.empty() || runs.back().first + runs.back().second != next)
        throw scene::InputError(o.input.string() + ": the parts do not hold each of its " +
                                std::to_string(view->chunkCount()) + " chunks once");
    const uint32_t levels = lod::pyramidLevels(header.grid.resolution, header.blockSize, v.pyramid);
    const lod::PyramidRangePlan plan = lod::planPyramidRanges(std::move(blocks), levels, wantedRanges);
    return nlohmann::json{{"levels", plan.levels}, {"splitLevel", plan.splitLevel}, {"rangeStarts", plan.rangeStarts}}.dump();
}

std::string voxelizeRange(const VoxelizeCommandOptions& o, const std::vector<std::filesystem::path>& parts,
                          const std::string& planText, size_t range, const std::filesystem::path& rangeFile) {
    const VoxelizeSettings v = voxelizeSettings(o);
    raster::ThreadLimit threadLimit(o.threads);
    const lod::PyramidRangePlan plan = planFromJson(planText);
    if (range >= plan.rangeCount()) throw std::invalid_argument("voxelizeRange: no such range in the plan");
    const double m0 = raster::nowMs();
    std::vector<voxel::PartialVoxelization> read;
    for (const std::filesystem::path& p : parts)
        read.push_back(voxel::readPartialVoxelization(p, plan.rangeBegin(range), plan.rangeEnd(range)));
    voxel::VoxelizeStats s;
    voxel::VoxelModel model = voxel::mergePartialVoxelizations(std::move(read), &s);
    const double mergeMs = raster::nowMs() - m0;
    AtomicOutputFile out(rangeFile);
    lod::buildPyramidRange(std::move(model), v.pyramid, plan.splitLevel, out.stream());
    out.commit();
    return nlohmann::json{{"conservativeVoxels", s.conservativeVoxels}, {"mergeMs", mergeMs}, {"woundInwards", s.woundInwards}}
        .dump();
}

int finishVoxelizeFromRanges(const VoxelizeCommandOptions& o, const std::vector<std::filesystem::path>& parts,
                             const std::string& planText, const std::vector<std::filesystem::path>& rangeFiles,
                             const std::vector<std::string>& rangeResults) {
    const VoxelizeSettings v = voxelizeSettings(o);
    raster::ThreadLimit threadLimit(o.threads);
    const double t0 = raster::nowMs();
    const std::unique_ptr<voxel::MeshView> view = openVoxelizeInput(o);
    const double openMs = raster::nowMs() - t0;
    const lod::PyramidRangePlan plan = planFromJson(planText);
    if (rangeFiles.size() != plan.rangeCount() || rangeResults.size() != plan.rangeCount())
        throw std::invalid_argument("finishVoxelizeFromRanges: not one range file and result per range of the plan");
    if (parts.empty()) throw std::invalid_argument("finishVoxelizeFromRanges: no parts");
    const voxel::VoxelModel header = voxel::readPartialVoxelizationIndex(parts[0]).part.header;
    const lod::PyramidRangeJoin join(header, rangeFiles, v.pyramid, plan);
    voxel::VoxelizeStats s;
    s.chunks = view->chunkCount();
    for (size_t i = 0; i < view->chunkCount(); ++i) s.triangles += view->chunkInfo(i).triangleCount;
    for (const std::string& r : rangeResults) {
        const nlohmann::json j = nlohmann::json::parse(r);
        s.conservativeVoxels += j.at("conservativeVoxels").get<uint64_t>();
        s.mergeMs += j.at("mergeMs").get<double>();
        s.woundInwards = j.at("woundInwards").get<bool>();  // every range merged the same parts' sums
    }
    for (const voxel::VoxelBlock& b : join.layout().blocks)
        if (b.level == 0) ++s.blocks, s.voxels += b.totalVoxels(), s.sourceTriangles += b.totalTriangles();
    requireVoxels(o, s.voxels, s.triangles);
    const double w0 = raster::nowMs();
    // Both files are complete before either is renamed into place.
    AtomicOutputFile cvox(o.out);
    std::unique_ptr<AtomicOutputFile> text;
    if (!o.exportVoxels.empty()) text = std::make_unique<AtomicOutputFile>(o.exportVoxels);
    join.write(cvox.stream(), text ? &text->stream() : nullptr);
    cvox.commit();
    if (text) text->commit();
    return reportVoxelize(o, v, s, join.stats(), join.layout().blocks.size(), openMs, raster::nowMs() - w0, t0);
}

int runIsosurfaceCommand(const IsosurfaceCommandOptions& o) {
    requireKind(o.out, scene::FileKind::VoxelModel, ".cvox", "the voxel model");
    requireOutputPath(o.out, "-o");
    requireOutputPath(o.exportVoxels, "--export-voxels");
    requireOutputPath(o.statsPath, "--stats");
    voxel::VolumeDesc d;
    d.dims = {o.dims[0], o.dims[1], o.dims[2]};
    if (d.dims.x == 0 || d.dims.y == 0 || d.dims.z == 0) throw scene::InputError("--dims: every dimension must be at least 1");
    if (o.type == "u8") d.type = voxel::SampleType::U8;
    else if (o.type == "u16") d.type = voxel::SampleType::U16;
    else if (o.type == "f32") d.type = voxel::SampleType::F32;
    else throw scene::InputError("--type " + o.type + ": expected u8, u16 or f32");
    voxel::IsosurfaceOptions io;
    io.iso = o.iso;
    if (o.normals == "regression") io.gradient = voxel::GradientEstimator::LinearRegression;
    else if (o.normals == "central") io.gradient = voxel::GradientEstimator::CentralDifferences;
    else throw scene::InputError("--normals " + o.normals + ": expected regression or central");
    raster::ThreadLimit threadLimit(o.threads);

    const double t0 = raster::nowMs();
    const uint64_t expected = uint64_t(d.dims.x) * d.dims.y * d.dims.z * voxel::sampleBytes(d.type);
    std::error_code ec;
    const uintmax_t size = std::filesystem::file_size(o.volume, ec);
    if (ec) throw scene::InputError(o.volume.string() + ": cannot read: " + ec.message());
    if (size != expected)
        throw scene::InputError(o.volume.string() + ": " + std::to_string(size) + " bytes, but " + std::to_string(d.dims.x) +
                                "x" + std::to_string(d.dims.y) + "x" + std::to_string(d.dims.z) + " " + o.type +
                                " samples need " + std::to_string(expected) + (size < expected ? " (truncated)" : ""));
    const std::string bytes = scene::readFileBytes(o.volume);
    const double readMs = raster::nowMs() - t0;
    voxel::IsosurfaceStats s;
    voxel::VoxelModel model = voxel::extractIsosurface(bytes, d, io, &s);
    if (s.voxels == 0)
        throw scene::InputError(o.volume.string() + ": no voxels: the surface at --iso " + formatNumber(o.iso) +
                                " is empty (no sample at or above it has a neighbour below it)");
    lod::PyramidOptions po;
    po.maxLevels = o.levels;
    lod::PyramidStats ps;
    lod::buildLodPyramid(model, po, &ps);
    double writeMs = 0;
    writeModelFiles(model, o.out, o.exportVoxels, writeMs);
    if (!o.quiet)
        std::printf("isosurface of %s at %g: %llu voxels in %zu blocks (%llu of %llu blocks skipped), %.0f ms "
                    "(read %.0f, extract %.0f, write %.0f) -> %s\n",
                    o.volume.string().c_str(), o.iso, (unsigned long long)s.voxels, model.blocks.size(),
                    (unsigned long long)s.blocksSkipped, (unsigned long long)s.blocks, raster::nowMs() - t0, readMs,
                    s.extractMs, writeMs, o.out.string().c_str());
    if (!o.statsPath.empty())
        writeJsonAtomically(o.statsPath, {{"input", o.volume.string()},
                                          {"samples", s.samples},
                                          {"voxels", s.voxels},
                                          {"blocks", s.blocks},
                                          {"blocksSkipped", s.blocksSkipped},
                                          {"lod", pyramidJson(ps)},
                                          {"peakResidentMib", peakResidentMib()},
                                          {"times", {{"readMs", readMs}, {"extractMs", s.extractMs}, {"writeMs", writeMs}}}});
    return 0;
}

int runInfoCommand(const InfoOptions& o) {
    if (scene::fileKindOf(o.file) == scene::FileKind::VoxelModel) {
        const voxel::VoxelModel m = voxel::readCvox(o.file);
        uint32_t levels = 0;
        for (const voxel::VoxelBlock& b : m.blocks) levels = std::max(levels, b.level + 1);
        std::printf("%s: voxel model, %u^3 (%s), %u level(s), %zu blocks of up to %u^3, %llu voxels, %llu source "
                    "triangles\n  grid origin (%.9g, %.9g, %.9g), extent %.9g (voxel %.9g)\n  colours: %s\n",
                    o.file.string().c_str(), m.grid.resolution, voxel::separabilityName(m.separability), levels,
                    m.blocks.size(), m.blockSize, (unsigned long long)m.voxelCount(),
                    (unsigned long long)m.triangleCount(), m.grid.origin.x, m.grid.origin.y, m.grid.origin.z,
                    m.grid.extent, m.grid.voxelSize(), m.hasColors ? "from the source" : "none (white)");
        return 0;
    }
    if (voxel::isGeometryStreamFile(o.file)) {
        const auto view = voxel::openMeshView(o.file, warnToStderr);
        uint64_t vertices = 0;
        for (size_t i = 0; i < view->chunkCount(); ++i) {
            view->readChunk(i);  // decompress and check every chunk
            vertices += view->chunkInfo(i).vertexCount;
        }
        glm::vec3 lo, hi;
        view->bounds(lo, hi);
        std::printf("%s: geometry stream, %zu chunks, %llu triangles, %llu vertices, %s\n  bounds (%.9g, %.9g, %.9g) - "
                    "(%.9g, %.9g, %.9g)\n",
                    o.file.string().c_str(), view->chunkCount(), (unsigned long long)view->triangleCount(),
                    (unsigned long long)vertices, view->hasColors() ? "with colours" : "no colours", lo.x, lo.y, lo.z,
                    hi.x, hi.y, hi.z);
        return 0;
    }
    throw scene::InputError(o.file.string() + ": info reads .cgs and .cvox files");
}

CLI::App* addVoxelizeCommand(CLI::App& app, VoxelizeCommandOptions& o) {
    CLI::App* v = app.add_subcommand(
        "voxelize", "Voxelize a mesh's surface with the adaptive octree rasterizer into a voxel model (.cvox)");
    v->add_option("mesh", o.input, "A .cgs, .ply, .ply.gz, .obj, .gltf or .glb file")->required();
    v->add_option("-o,--out", o.out, "Output voxel model, .cvox")->required();
    v->add_option("--resolution", o.resolution, "Voxels along the longest side: a power of two from 2 to 65536")
        ->capture_default_str();
    v->add_option("--separability", o.separability,
                  "conservative (every voxel the surface touches), 26 or 6 (thinner, still separating inside "
                  "from outside for 26- or 6-connected paths)")
        ->capture_default_str();
    v->add_option("--export-voxels", o.exportVoxels,
                  "Also write the voxels as text: '# cuberille voxels R ox oy oz extent', then 'i j k' per voxel");
    v->add_flag("--no-source-triangles", o.noSourceTriangles,
                "Do not keep the source triangles clipped per block (smaller file; no hybrid rendering)");
    v->add_option("--levels", o.levels, "LOD levels to write (each halves the resolution); 0: down to one 64^3 block")
        ->capture_default_str();
    v->add_option("--simplify", o.simplify, "Simplification: parallel or serial (streaming); identical output")
        ->capture_default_str();
    v->add_option("--threads", o.threads, "Worker threads (0 = all cores)")->capture_default_str();
    v->add_option("--stats", o.statsPath, "Write counts, timings and peak memory as JSON");
    v->add_flag("--quiet", o.quiet, "Print nothing on success");
    return v;
}

VoxelizeCommandOptions parseVoxelizeArguments(const std::vector<std::string>& arguments) {
    VoxelizeCommandOptions o;
    parseSubcommandArguments("voxelize", arguments, [&](CLI::App& app) { addVoxelizeCommand(app, o); });
    return o;
}

}  // namespace cuberille::apps
