// The `cuberille` Python module's native part (`cuberille._cuberille`): a thin binding of the
// renderer library (render/renderer.h). Keyword arguments are FrameSettings' fields under their
// command-line names (`--pixel-error` is `pixel_error`), parsed by the same functions, so a bad
// value raises cuberille.InputError with the message the command line prints. The pure-Python
// part (python/cuberille/__init__.py, testing.py) builds on this.

#include <cstring>
#include <memory>
#include <optional>
#include <string>

#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "apps/accuracy_command.h"
#include "apps/batch_command.h"
#include "apps/fly_command.h"
#include "apps/png_file.h"
#include "apps/render_command.h"
#include "apps/render_options_cli.h"
#include "apps/voxel_commands.h"
#include "render/display_image.h"
#include "render/fly.h"
#include "render/renderer.h"
#include "scene/input_error.h"

namespace py = pybind11;
using namespace cuberille;

namespace {

glm::vec3 vector3(const py::handle& value, const char* name) {
    const auto v = value.cast<std::vector<float>>();
    if (v.size() != 3) throw scene::InputError(std::string(name) + ": expected three numbers (x, y, z)");
    return {v[0], v[1], v[2]};
}

// Each keyword is one FrameSettings field; an unknown keyword is a TypeError naming it, as
// Python's own calls do.
render::FrameSettings frameSettings(int width, int height, int msaa, const py::kwargs& kwargs) {
    render::FrameSettings f;
    f.width = width;
    f.height = height;
    f.msaa = msaa;
    std::optional<scene::CameraPlacement> placement;
    auto place = [&]() -> scene::CameraPlacement& {
        if (!placement) placement.emplace();
        return *placement;
    };
    bool eyeGiven = false;
    for (const auto& [key, value] : kwargs) {
        const std::string k = key.cast<std::string>();
        if (k == "threads") f.threads = value.cast<int>();
        else if (k == "view") f.view = render::parseView(value.cast<std::string>());
        else if (k == "azimuth") f.azimuth = value.cast<float>();
        else if (k == "elevation") f.elevation = value.cast<float>();
        else if (k == "camera_index") f.cameraIndex = value.cast<int>();
        else if (k == "eye") place().eye = vector3(value, "eye"), eyeGiven = true;
        else if (k == "target") place().target = vector3(value, "target");
        else if (k == "up") place().up = vector3(value, "up");
        else if (k == "fov") place().verticalFovDegrees = value.cast<float>();
        else if (k == "orbit") f.orbitDegrees = value.cast<float>();
        else if (k == "time") f.timeSeconds = value.cast<float>();
        else if (k == "animation") f.animation = py::isinstance<py::int_>(value) ? std::to_string(value.cast<int>()) : value.cast<std::string>();
        else if (k == "zoom") f.zoom = value.cast<float>();
        else if (k == "orthographic") f.orthographic = value.cast<bool>();
        else if (k == "legend") f.legend = value.cast<bool>();
        else if (k == "frustum_cull") f.frustumCull = value.cast<bool>();
        else if (k == "ground") f.ground = value.cast<bool>();
        else if (k == "shadow_catcher") f.shadowCatcher = value.cast<bool>();
        else if (k == "bvh_update") f.bvhUpdate = render::parseBvhUpdate(value.cast<std::string>());
        else if (k == "accel") render::applyAccel(value.cast<std::string>(), f);
        else if (k == "renderer") f.renderer = render::parseRenderer(value.cast<std::string>());
        else if (k == "frame_visibility") f.frameVisibility = render::parseFrameVisibility(value.cast<std::string>());
        else if (k == "supersample") f.supersample = value.cast<int>();
        else if (k == "texture_filter") f.textureFilter = render::parseTextureFilter(value.cast<std::string>());
        else if (k == "depth") f.depth = render::parseDepthConvention(value.cast<std::string>());
        else if (k == "pixel_error") f.pixelError = value.cast<float>();
        else if (k == "voxel_resolution") f.voxelResolution = value.cast<uint32_t>();
        else if (k == "no_hybrid") f.noHybrid = value.cast<bool>();
        else if (k == "no_occlusion") f.noOcclusion = value.cast<bool>();
        else if (k == "warmup") f.warmup = value.cast<int>();
        else if (k == "shadows") f.shadows.mode = render::parseShadowMode(value.cast<std::string>());
        else if (k == "soft") f.shadows.soft = value.cast<bool>();
        else if (k == "light_radius") f.shadows.lightRadius = value.cast<float>();
        else if (k == "shadow_map_size") f.shadows.mapSizeTexels = value.cast<int>();
        else if (k == "soft_samples") f.shadows.softSamplesPerSide = value.cast<int>();
        else if (k == "shadow_focus") f.shadows.focus = render::parseMapFocus(value.cast<std::string>());
        else if (k == "ao") f.ambientOcclusion.raysPerPixel = value.cast<int>();
        else if (k == "ao_distance") f.ambientOcclusion.maxDistance = value.cast<float>();
        else if (k == "environment") f.environment = py::str(value).cast<std::string>();  // a name or a path-like
        else if (k == "environment_intensity") f.environmentIntensity = value.cast<float>();
        else if (k == "background") {
            const auto v = value.cast<std::vector<float>>();
            if (v.size() != 3 && v.size() != 4) throw scene::InputError("background: expected (r, g, b) or (r, g, b, a), each in [0, 1]");
            glm::vec4 b(0.0f, 0.0f, 0.0f, 1.0f);
            for (size_t i = 0; i < v.size(); ++i) {
                if (!(v[i] >= 0.0f && v[i] <= 1.0f)) throw scene::InputError("background: each value in [0, 1]");
                b[int(i)] = v[i];
            }
            f.background = b;
        } else {
            throw py::type_error("render() got an unexpected keyword argument '" + k + "'");
        }
    }
    if (placement && !eyeGiven) throw scene::InputError("--target, --up and --fov: only with --eye");
    f.placement = placement;
    return f;
}

/// A scene loaded once; each render() reuses it. The statistics of the last render are kept.
class PyScene {
public:
    PyScene(const std::string& path, float detail, const std::string& upAxis) {
        render::SceneOptions options;
        options.detail = detail;
        if (upAxis != "y" && upAxis != "z") throw scene::InputError("--up-axis: '" + upAxis + "' is not y or z");
        options.zUp = upAxis == "z";
        scene_ = std::make_unique<render::LoadedScene>(path, options,
                                                       [this](const std::string& w) { warnings_.push_back(w); });
    }

    py::array render(int width, int height, int msaa, bool linear, const py::kwargs& kwargs) {
        const render::FrameSettings f = frameSettings(width, height, msaa, kwargs);
        render::RenderResult r;
        std::vector<uint8_t> pixels;
        {
            py::gil_scoped_release release;  // other Python threads run while the frame renders
            r = render::render(*scene_, f);
            if (!linear) pixels = render::displayPixels(*scene_, f, r);
        }
        stats_ = render::statsJson(scene_->name(), f, r);
        if (linear) {
            py::array_t<float> out({r.image.height, r.image.width, 4});
            std::memcpy(out.mutable_data(), r.image.rgba.data(), r.image.rgba.size() * sizeof(float));
            return out;
        }
        py::array_t<uint8_t> out({r.image.height, r.image.width, 4});
        std::memcpy(out.mutable_data(), pixels.data(), pixels.size());
        return out;
    }

    const std::string& statsJson() const { return stats_; }
    const std::string& name() const { return scene_->name(); }
    std::vector<std::string> animations() const { return scene_->animations(); }
    const std::vector<std::string>& warnings() const { return warnings_; }
    size_t cameras() const { return render::cameraCount(*scene_); }
    const render::LoadedScene& loaded() const { return *scene_; }
    double loadMs() const { return scene_->loadMs(); }

private:
    std::unique_ptr<render::LoadedScene> scene_;
    std::vector<std::string> warnings_;
    std::string stats_;
};

// A `render` command line (or a batch job line) read by the tool's own parser, so that a program
// driving the tool's work — the distributed runner, python/cuberille/dask — takes the same options,
// refuses the same input with the same messages, and writes the same files: run() renders a
// contiguous run of the command's frames into their files.
class PyRenderCommand {
public:
    explicit PyRenderCommand(apps::RenderOptions o) : o_(std::move(o)) {}

    static PyRenderCommand fromArguments(const std::vector<std::string>& arguments) {
        apps::RenderOptions o = apps::parseRenderArguments(arguments);
        apps::checkRenderCommand(o);
        return PyRenderCommand(std::move(o));
    }
    static PyRenderCommand fromJobLine(const std::string& line) { return PyRenderCommand(apps::parseBatchJob(line, true)); }

    // Each frame's --stats object as JSON text, in order. `threadsIfUnset` stands for the
    // command's --threads 0 (all cores): a worker sharing its machine with others gets its share.
    std::vector<std::string> run(const PyScene& scene, int first, int count, int threadsIfUnset) {
        apps::RenderOptions o = o_;
        if (o.threads == 0) o.threads = threadsIfUnset;
        nlohmann::json frames;
        {
            py::gil_scoped_release release;
            frames = apps::renderFrameRun(scene.loaded(), o, first, count);
        }
        std::vector<std::string> out;
        for (const auto& f : frames) out.push_back(f.dump());
        return out;
    }

    void writeStats(const std::vector<std::string>& frames) const {
        nlohmann::json all = nlohmann::json::array();
        for (const auto& f : frames) all.push_back(nlohmann::json::parse(f));
        apps::writeRenderStats(o_, all);
    }

    const apps::RenderOptions& options() const { return o_; }
    std::string frameFile(int index) const { return apps::frameFile(o_, index).string(); }

private:
    apps::RenderOptions o_;
};

// A `cuberille accuracy` command line read by the tool's own parser, and the command's three steps
// taken apart (apps/accuracy_command.h) for the distributed runner: plan() here (one probe render),
// run() for each of the plan's runs wherever it is sent, finish() here with every run's row. Runs
// and rows travel as JSON text. `executable` is the cuberille program every run starts, a path
// that must name it on every machine that runs one; `threadsIfUnset` stands for --threads 0.
class PyAccuracyCommand {
public:
    static PyAccuracyCommand fromArguments(const std::vector<std::string>& arguments) {
        PyAccuracyCommand c;
        c.o_ = apps::parseAccuracyArguments(arguments);
        return c;
    }

    std::vector<std::string> plan(const std::string& executable, int threadsIfUnset) {
        {
            py::gil_scoped_release release;
            plan_ = apps::planAccuracy(options(executable, threadsIfUnset));
        }
        std::vector<std::string> runs;
        for (const apps::AccuracyRun& r : plan_->runs) runs.push_back(apps::accuracyRunJson(r).dump());
        return runs;
    }

    std::string run(const std::string& runJson, const std::string& executable, int threadsIfUnset) const {
        const apps::AccuracyRun run = apps::accuracyRunFromJson(nlohmann::json::parse(runJson));
        const apps::AccuracyOptions o = options(executable, threadsIfUnset);
        py::gil_scoped_release release;
        return apps::accuracyRowJson(apps::runAccuracySetting(o, run)).dump();
    }

    size_t finish(const std::vector<std::string>& rowsJson, const std::string& machine) {
        if (!plan_) throw std::logic_error("AccuracyCommand.finish: plan() first");
        std::vector<apps::AccuracyRow> rows;
        for (const std::string& r : rowsJson) rows.push_back(apps::accuracyRowFromJson(nlohmann::json::parse(r)));
        apps::AccuracyPlan plan = std::move(*plan_);
        plan_.reset();
        if (!machine.empty()) plan.report.machine = machine;
        py::gil_scoped_release release;
        return apps::finishAccuracy(std::move(plan), std::move(rows)).rows.size();
    }

    const apps::AccuracyOptions& options() const { return o_; }

private:
    apps::AccuracyOptions options(const std::string& executable, int threadsIfUnset) const {
        apps::AccuracyOptions o = o_;
        o.executable = executable;
        if (o.threads == 0) o.threads = threadsIfUnset;
        return o;
    }

    apps::AccuracyOptions o_;
    std::optional<apps::AccuracyPlan> plan_;
};

// A `cuberille fly` command line read by the tool's own parser, flown in runs of its path's frames
// (render::FlySettings::firstFrame) for the distributed runner: run() flies frames [first, first +
// count) from a cold start and writes them (final.png by the run that ends the path), returning
// its result as JSON text; finish() joins every run's result as one flight and writes --stats and
// --plot and prints the summary, as the command does.
class PyFlyCommand {
public:
    static PyFlyCommand fromArguments(const std::vector<std::string>& arguments) {
        PyFlyCommand c;
        c.o_ = apps::parseFlyArguments(arguments);
        return c;
    }

    std::string run(int first, int count, int threadsIfUnset) const {
        apps::FlyOptions o = o_;
        o.firstFrame = first, o.runFrames = count, o.quiet = true;
        if (o.threads == 0) o.threads = threadsIfUnset;
        if (!o.outDir.empty()) std::filesystem::create_directories(o.outDir);
        py::gil_scoped_release release;
        return apps::flyResultJson(apps::runFly(o)).dump();
    }

    int finish(const std::vector<std::string>& runs) const {
        std::vector<apps::FlyResult> results;
        for (const std::string& r : runs) results.push_back(apps::flyResultFromJson(nlohmann::json::parse(r)));
        py::gil_scoped_release release;
        return apps::finishFlyCommand(o_, apps::joinFlyRuns(std::move(results)));
    }

    const apps::FlyOptions& options() const { return o_; }

private:
    apps::FlyOptions o_;
};

// A `cuberille voxelize` command line read by the tool's own parser, taken apart for the
// distributed runner (apps/voxel_commands.h): run() voxelizes a run of the input's chunks into a
// part file; plan_ranges() cuts the model's blocks into ranges; merge_range() merges one range
// from every part and builds its pyramid up to the split level into a range file; finish() joins
// the ranges into what the command writes (the single-machine files bit for bit).
class PyVoxelizeCommand {
public:
    static PyVoxelizeCommand fromArguments(const std::vector<std::string>& arguments) {
        PyVoxelizeCommand c;
        c.o_ = apps::parseVoxelizeArguments(arguments);
        return c;
    }
    size_t chunkCount() const {
        py::gil_scoped_release release;
        return apps::voxelizeChunkCount(o_);
    }
    void run(size_t first, size_t count, const std::string& part, int threadsIfUnset) const {
        apps::VoxelizeCommandOptions o = o_;
        o.quiet = true;
        if (o.threads == 0) o.threads = threadsIfUnset;
        py::gil_scoped_release release;
        apps::voxelizeChunkRun(o, first, count, part);
    }
    std::string planRanges(const std::vector<std::string>& parts, size_t wantedRanges) const {
        const std::vector<std::filesystem::path> paths(parts.begin(), parts.end());
        py::gil_scoped_release release;
        return apps::planVoxelizeRanges(o_, paths, wantedRanges);
    }
    std::string mergeRange(const std::vector<std::string>& parts, const std::string& plan, size_t range,
                           const std::string& rangeFile, int threadsIfUnset) const {
        apps::VoxelizeCommandOptions o = o_;
        if (o.threads == 0) o.threads = threadsIfUnset;
        const std::vector<std::filesystem::path> paths(parts.begin(), parts.end());
        py::gil_scoped_release release;
        return apps::voxelizeRange(o, paths, plan, range, rangeFile);
    }
    int finish(const std::vector<std::string>& parts, const std::string& plan, const std::vector<std::string>& ranges,
               const std::vector<std::string>& results) const {
        const std::vector<std::filesystem::path> partPaths(parts.begin(), parts.end()), rangePaths(ranges.begin(), ranges.end());
        py::gil_scoped_release release;
        return apps::finishVoxelizeFromRanges(o_, partPaths, plan, rangePaths, results);
    }
    const apps::VoxelizeCommandOptions& options() const { return o_; }

private:
    apps::VoxelizeCommandOptions o_;
};

// A flight through a streamed voxel model (render/fly.h): every frame's statistics as a dict, and
// the settled last view as uint8 sRGB RGBA.
py::dict fly(const std::string& model, const std::string& path, int frames, int width, int height, int msaa, int threads,
             double budgetMib, double uploadLimitMib, const std::string& refine, float pixelError, int settleFrames) {
    render::FlySettings s;
    s.model = model, s.path = path, s.frames = frames, s.width = width, s.height = height, s.msaa = msaa;
    s.threads = threads, s.budgetMib = budgetMib, s.uploadLimitMib = uploadLimitMib, s.refine = refine;
    s.pixelError = pixelError, s.settleFrames = settleFrames;
    render::FlyResult r;
    std::vector<uint8_t> pixels;
    {
        py::gil_scoped_release release;
        r = render::fly(s);
        pixels = render::displayRgba8(r.finalImage, false);
    }
    py::list perFrame;
    for (const lod::FlightFrame& f : r.frames) {
        py::dict d;
        d["index"] = f.index, d["settling"] = f.settling, d["frame_ms"] = f.frameMs, d["traversal_ms"] = f.traversalMs;
        d["io_wait_ms"] = f.ioWaitMs, d["upload_ms"] = f.uploadMs, d["raster_ms"] = f.rasterMs;
        d["faces"] = f.voxel.facesEmitted, d["loaded_bytes"] = f.streaming.loadedBytes;
        d["missing_blocks"] = f.voxel.missingBlocks, d["occlusion_culled"] = f.voxel.occlusionCulled;
        // The CSV's waste figures (issue 25): faces left out before drawing, and faces per covered pixel.
        d["faces_between_samples"] = f.voxel.facesBetweenSamples, d["faces_behind_depth"] = f.voxel.facesBehindDepth;
        d["covered_pixels"] = f.voxel.coveredPixels, d["faces_per_covered_pixel"] = f.voxel.facesPerCoveredPixel();
        perFrame.append(d);
    }
    py::array_t<uint8_t> image({r.finalImage.height, r.finalImage.width, 4});
    std::memcpy(image.mutable_data(), pixels.data(), pixels.size());
    py::dict result;
    result["frames"] = perFrame, result["final_image"] = image, result["settled"] = r.settled;
    result["bytes_read_from_disk"] = r.bytesReadFromDisk, result["peak_held_bytes"] = r.peakHeldBytes;
    result["budget_bytes"] = r.budgetBytes, result["open_ms"] = r.openMs, result["warnings"] = r.warnings;
    return result;
}

py::array_t<uint8_t> readPng8(const std::string& path) {
    const raster::Image image = apps::readPng(path);
    py::array_t<uint8_t> out({image.height, image.width, 4});
    uint8_t* p = out.mutable_data();
    for (size_t i = 0; i < image.rgba.size(); ++i) p[i] = uint8_t(std::lround(image.rgba[i] * 255.0f));
    return out;
}

void writePng8(const std::string& path, py::array_t<uint8_t, py::array::c_style | py::array::forcecast> pixels) {
    if (pixels.ndim() != 3 || (pixels.shape(2) != 3 && pixels.shape(2) != 4))
        throw py::value_error("write_png: expected an array of shape (height, width, 3 or 4)");
    const std::vector<uint8_t> bytes(pixels.data(), pixels.data() + pixels.size());
    apps::writePng8(path, int(pixels.shape(1)), int(pixels.shape(0)), int(pixels.shape(2)), bytes);
}

}  // namespace

PYBIND11_MODULE(_cuberille, m) {
    m.doc() = "Cuberille's renderer (render/renderer.h); use the `cuberille` package, not this module.";
    static py::exception<scene::InputError> inputError(m, "InputError", PyExc_ValueError);
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const scene::InputError& e) {
            inputError(e.what());
        }
    });
    py::class_<PyScene>(m, "Scene")
        .def(py::init<const std::string&, float, const std::string&>(), py::arg("path"), py::arg("detail") = 1.0f,
             py::arg("up_axis") = "y")
        .def("render", &PyScene::render, py::arg("width") = 1280, py::arg("height") = 720, py::arg("msaa") = 1,
             py::arg("linear") = false)
        .def_property_readonly("stats_json", &PyScene::statsJson)
        .def_property_readonly("name", &PyScene::name)
        .def_property_readonly("animations", &PyScene::animations)
        .def_property_readonly("warnings", &PyScene::warnings)
        .def_property_readonly("cameras", &PyScene::cameras)
        .def_property_readonly("load_ms", &PyScene::loadMs);
    py::class_<PyRenderCommand>(m, "RenderCommand")
        .def_static("from_arguments", &PyRenderCommand::fromArguments, py::arg("arguments"),
                    "`cuberille render`'s arguments (the scene and options), checked as the command checks them")
        .def_static("from_job_line", &PyRenderCommand::fromJobLine, py::arg("line"),
                    "One line of a `cuberille batch` jobs file, checked as batch checks it")
        .def("run", &PyRenderCommand::run, py::arg("scene"), py::arg("first"), py::arg("count"), py::arg("threads_if_unset") = 0,
             "Renders and writes frames [first, first + count); each frame's stats as JSON text")
        .def("write_stats", &PyRenderCommand::writeStats, py::arg("frames"), "Writes --stats from every frame's JSON text")
        .def("frame_file", &PyRenderCommand::frameFile, py::arg("index"))
        .def_property_readonly("frame_count", [](const PyRenderCommand& c) { return apps::frameCount(c.options()); })
        .def_property_readonly("scene", [](const PyRenderCommand& c) { return c.options().scene; })
        .def_property_readonly("detail", [](const PyRenderCommand& c) { return c.options().detail; })
        .def_property_readonly("up_axis", [](const PyRenderCommand& c) { return std::string(c.options().zUp ? "z" : "y"); })
        .def_property_readonly("stats", [](const PyRenderCommand& c) { return c.options().statsPath.string(); });
    py::class_<PyAccuracyCommand>(m, "AccuracyCommand")
        .def_static("from_arguments", &PyAccuracyCommand::fromArguments, py::arg("arguments"),
                    "`cuberille accuracy`'s arguments (the scene and options), checked as the command checks them")
        .def("plan", &PyAccuracyCommand::plan, py::arg("executable"), py::arg("threads_if_unset") = 0,
             "Probes the scene and lays out the sweep: its runs as JSON text, the ground truth last")
        .def("run", &PyAccuracyCommand::run, py::arg("run"), py::arg("executable"), py::arg("threads_if_unset") = 0,
             "Renders one run of the plan here; its row as JSON text")
        .def("finish", &PyAccuracyCommand::finish, py::arg("rows"), py::arg("machine") = "",
             "Compares every row with the ground truth and writes the report; the number of rows")
        .def_property_readonly("out_dir", [](const PyAccuracyCommand& c) { return c.options().outDir.string(); })
        .def_property_readonly("quiet", [](const PyAccuracyCommand& c) { return c.options().quiet; });
    py::class_<PyFlyCommand>(m, "FlyCommand")
        .def_static("from_arguments", &PyFlyCommand::fromArguments, py::arg("arguments"),
                    "`cuberille fly`'s arguments (the model and options), checked as the command checks them")
        .def("run", &PyFlyCommand::run, py::arg("first"), py::arg("count"), py::arg("threads_if_unset") = 0,
             "Flies the path's frames [first, first + count) from a cold start and writes them; the result as JSON text")
        .def("finish", &PyFlyCommand::finish, py::arg("runs"),
             "Joins the runs' results as one flight; writes --stats and --plot and prints the summary")
        .def("frame_file", [](const PyFlyCommand& c, int frame) { return apps::flyFrameFile(c.options(), frame).string(); })
        .def_property_readonly("frames", [](const PyFlyCommand& c) { return c.options().frames; })
        .def_property_readonly("save_every", [](const PyFlyCommand& c) { return c.options().saveEvery; })
        .def_property_readonly("out_dir", [](const PyFlyCommand& c) { return c.options().outDir.string(); })
        .def_property_readonly("stats", [](const PyFlyCommand& c) { return c.options().statsPath.string(); })
        .def_property_readonly("plot", [](const PyFlyCommand& c) { return c.options().plotPath.string(); })
        .def_property_readonly("quiet", [](const PyFlyCommand& c) { return c.options().quiet; });
    py::class_<PyVoxelizeCommand>(m, "VoxelizeCommand")
        .def_static("from_arguments", &PyVoxelizeCommand::fromArguments, py::arg("arguments"),
                    "`cuberille voxelize`'s arguments (the mesh and options), read by the command's own parser")
        .def("chunk_count", &PyVoxelizeCommand::chunkCount, "The input's chunks (checks the options and opens it)")
        .def("run", &PyVoxelizeCommand::run, py::arg("first"), py::arg("count"), py::arg("part"),
             py::arg("threads_if_unset") = 0, "Voxelizes chunks [first, first + count) into the part file")
        .def("plan_ranges", &PyVoxelizeCommand::planRanges, py::arg("parts"), py::arg("wanted_ranges"),
             "The ranges of blocks to merge (JSON), from the parts' block indexes; checks each chunk is in one part")
        .def("merge_range", &PyVoxelizeCommand::mergeRange, py::arg("parts"), py::arg("plan"), py::arg("range"),
             py::arg("range_file"), py::arg("threads_if_unset") = 0,
             "Merges one range of blocks from every part and builds its pyramid up to the plan's split level")
        .def("finish", &PyVoxelizeCommand::finish, py::arg("parts"), py::arg("plan"), py::arg("ranges"), py::arg("results"),
             "Joins the range files (in the plan's order) and writes the .cvox, --export-voxels and --stats; prints the summary")
        .def_property_readonly("out", [](const PyVoxelizeCommand& c) { return c.options().out.string(); })
        .def_property_readonly("stats", [](const PyVoxelizeCommand& c) { return c.options().statsPath.string(); })
        .def_property_readonly("export_voxels", [](const PyVoxelizeCommand& c) { return c.options().exportVoxels.string(); })
        .def_property_readonly("quiet", [](const PyVoxelizeCommand& c) { return c.options().quiet; });
    m.def("fly", &fly, py::arg("model"), py::arg("path") = "orbit", py::arg("frames") = 120, py::arg("width") = 1280,
          py::arg("height") = 720, py::arg("msaa") = 4, py::arg("threads") = 0, py::arg("budget_mib") = 1024.0,
          py::arg("upload_limit_mib") = 0.0, py::arg("refine") = "full", py::arg("pixel_error") = 1.0f,
          py::arg("settle_frames") = 1000);
    m.def("read_png", &readPng8, py::arg("path"), "A PNG as a (height, width, 4) uint8 array (8-bit files exactly).");
    m.def("write_png", &writePng8, py::arg("path"), py::arg("pixels"), "An (h, w, 3|4) uint8 array as an sRGB PNG.");
}
