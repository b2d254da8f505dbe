// The `cuberille` command-line tool. Exit codes (DESIGN.md): 0 success, 1 failure while
// working, 2 bad usage or bad input.

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>
#include <exception>

#include <CLI/CLI.hpp>

#include "apps/accuracy_command.h"
#include "apps/explain_command.h"
#include "apps/fly_command.h"
#include "apps/image_io.h"
#include "apps/batch_command.h"
#include "apps/render_command.h"
#include "apps/render_options_cli.h"
#include "apps/voxel_commands.h"
#include "apps/worker_threads.h"
#include "raster/instruction_set.h"
#include "scene/input_error.h"
#include "scene/procedural.h"

namespace {

constexpr int kExitFailure = 1;
constexpr int kExitBadInput = 2;


void addExplainCommand(CLI::App& app, cuberille::apps::ExplainOptions& o) {
    CLI::App* explain = app.add_subcommand(
        "explain", "Show the rasterization pipeline stage by stage for a .tri scene or one triangle, as magnified images");
    explain->add_option("scene", o.scene, "A .tri scene (or give --triangle)");
    explain->add_option("--triangle", o.triangle, "One triangle \"x0 y0 x1 y1 x2 y2\" in pixels, of value 1");
    explain->add_option("--out-dir", o.outDir, "Directory for the stage images and 3-edges.csv")->required();
    explain->add_option("--width", o.width, "Framebuffer width (0: the scene's bounds and a margin)");
    explain->add_option("--height", o.height, "Framebuffer height (0: the scene's bounds and a margin)");
    explain->add_option("--scale", o.scale, "Image pixels per framebuffer pixel, 4..64")->capture_default_str();
    explain->add_option("--row", o.row, "The row whose edge values 3-edges shows and writes (default: the triangle's middle)");
    explain->add_option("--triangle-index", o.triangleIndex, "The triangle whose set-up and edges are drawn")
        ->capture_default_str();
    explain->add_flag("--quiet", o.quiet, "Print nothing on success");
}

void addPackCommand(CLI::App& app, cuberille::apps::PackOptions& o) {
    CLI::App* pack = app.add_subcommand(
        "pack", "Convert a mesh to a geometry stream (.cgs): LZ4-compressed chunks the voxelizer reads in parallel");
    pack->add_option("mesh", o.input, "A .ply, .ply.gz, .obj, .gltf, .glb (static pose) or .cgs file")->required();
    pack->add_option("-o,--out", o.out, "Output geometry stream, .cgs")->required();
    pack->add_option("--chunk-triangles", o.chunkTriangles, "Triangles per chunk")->capture_default_str();
    pack->add_option("--stats", o.statsPath, "Write counts and timings as JSON");
    pack->add_flag("--quiet", o.quiet, "Print nothing on success");
}

void addIsosurfaceCommand(CLI::App& app, cuberille::apps::IsosurfaceCommandOptions& o) {
    CLI::App* iso = app.add_subcommand(
        "isosurface", "Surface voxels of a raw volume's iso-surface into a voxel model (.cvox)");
    iso->add_option("volume", o.volume, "Raw samples, x fastest, little-endian")->required();
    iso->add_option("--dims", o.dims, "Samples along x, y and z")->required();
    iso->add_option("--type", o.type, "Sample type: u8, u16 or f32")->capture_default_str();
    iso->add_option("--iso", o.iso, "Iso-value: samples >= it are inside")->required();
    iso->add_option("-o,--out", o.out, "Output voxel model, .cvox")->required();
    iso->add_option("--normals", o.normals, "Gradient estimator: regression (3x3x3 linear regression) or central")
        ->capture_default_str();
    iso->add_option("--levels", o.levels, "LOD levels to write; 0: down to one 64^3 block")->capture_default_str();
    iso->add_option("--export-voxels", o.exportVoxels, "Also write the voxels as text (see voxelize)");
    iso->add_option("--threads", o.threads, "Worker threads (0 = all cores)")->capture_default_str();
    iso->add_option("--stats", o.statsPath, "Write counts and timings as JSON");
    iso->add_flag("--quiet", o.quiet, "Print nothing on success");
}

void addInfoCommand(CLI::App& app, cuberille::apps::InfoOptions& o) {
    CLI::App* info = app.add_subcommand("info", "Describe a geometry stream (.cgs) or voxel model (.cvox), checking all of it");
    info->add_option("file", o.file, "A .cgs or .cvox file")->required();
}

// Typos: the name among `names` nearest to `typed` by edit distance (Levenshtein), or "" when
// none is within a third of its length (so `rendr` suggests `render`, `xyz` nothing).
std::string closestName(const std::string& typed, const std::vector<std::string>& names) {
    std::string best;
    size_t bestDistance = std::max<size_t>(1, typed.size() / 3) + 1;
    for (const std::string& name : names) {
        std::vector<size_t> row(name.size() + 1);
        for (size_t j = 0; j <= name.size(); ++j) row[j] = j;
        for (size_t i = 1; i <= typed.size(); ++i) {
            size_t diagonal = row[0];
            row[0] = i;
            for (size_t j = 1; j <= name.size(); ++j) {
                const size_t above = row[j];
                row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (typed[i - 1] == name[j - 1] ? 0 : 1)});
                diagonal = above;
            }
        }
        if (row[name.size()] < bestDistance) bestDistance = row[name.size()], best = name;
    }
    return best;
}

std::string didYouMean(const std::string& typed, const std::vector<std::string>& names) {
    const std::string near = closestName(typed, names);
    return near.empty() ? "" : "; did you mean '" + near + "'?";
}

// A first word that is no subcommand: named, with the nearest one and the list (CLI11 alone says
// "A subcommand is required").
bool reportUnknownSubcommand(const CLI::App& app, int argc, char** argv) {
    if (argc < 2 || argv[1][0] == '-') return false;
    std::vector<std::string> names;
    for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) names.push_back(sub->get_name());
    const std::string typed = argv[1];
    if (std::find(names.begin(), names.end(), typed) != names.end()) return false;
    std::string all;
    for (const std::string& n : names) all += (all.empty() ? "" : ", ") + n;
    std::fprintf(stderr, "cuberille: '%s' is not a command%s (commands: %s)\n", typed.c_str(),
                 didYouMean(typed, names).c_str(), all.c_str());
    return true;
}

// Options the chosen subcommand does not have, each with the nearest one it has.
void reportUnknownOptions(CLI::App& app, int argc, char** argv) {
    const std::vector<CLI::App*> chosen = app.get_subcommands();
    if (chosen.empty()) return;
    std::vector<std::string> names;
    for (const CLI::Option* option : chosen.front()->get_options())
        for (const std::string& n : option->get_lnames()) names.push_back("--" + n);
    for (int i = 2; i < argc; ++i) {
        const std::string word = argv[i];
        if (word.rfind("--", 0) != 0) continue;
        const std::string name = word.substr(0, word.find('='));
        if (std::find(names.begin(), names.end(), name) == names.end())
            std::fprintf(stderr, "cuberille %s: unknown option %s%s\n", chosen.front()->get_name().c_str(), name.c_str(),
                         didYouMean(name, names).c_str());
    }
}

}  // namespace

int main(int argc, char** argv) {
    const cuberille::apps::WorkerThreadsJoinedAtExit workerThreads;  // first in, last out
    CLI::App app{"cuberille: a CPU renderer modelled on the GPU rasterization pipeline", "cuberille"};
    app.require_subcommand(1);
    app.set_version_flag("--version", std::string("cuberille ") + CUBERILLE_VERSION);
    cuberille::apps::RenderOptions renderOptions;
    cuberille::apps::RenderNames renderNames;
    cuberille::apps::addRenderCommand(app, renderOptions, renderNames);
    cuberille::apps::BatchOptions batchOptions;
    cuberille::apps::addBatchCommand(app, batchOptions);
    cuberille::apps::PackOptions packOptions;
    addPackCommand(app, packOptions);
    cuberille::apps::VoxelizeCommandOptions voxelizeOptions;
    cuberille::apps::addVoxelizeCommand(app, voxelizeOptions);
    cuberille::apps::IsosurfaceCommandOptions isosurfaceOptions;
    addIsosurfaceCommand(app, isosurfaceOptions);
    cuberille::apps::InfoOptions infoOptions;
    addInfoCommand(app, infoOptions);
    cuberille::apps::FlyOptions flyOptions;
    cuberille::apps::addFlyCommand(app, flyOptions);
    cuberille::apps::ExplainOptions explainOptions;
    addExplainCommand(app, explainOptions);
    cuberille::apps::AccuracyOptions accuracyOptions;
    cuberille::apps::addAccuracyCommand(app, accuracyOptions);

    if (reportUnknownSubcommand(app, argc, argv)) return kExitBadInput;
    try {
        app.parse(argc, argv);
    } catch (const CLI::ExtrasError& e) {
        app.exit(e);
        reportUnknownOptions(app, argc, argv);
        return kExitBadInput;
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        app.exit(e);
        return kExitBadInput;
    }
    cuberille::apps::registerEnvironmentReaders();

    try {
        cuberille::raster::useInstructionSetFromEnvironment();
    } catch (const std::invalid_argument& e) {
        std::fprintf(stderr, "cuberille: %s\n", e.what());
        return kExitBadInput;
    }
    try {
        if (app.got_subcommand("render")) {
            cuberille::apps::applyRenderNames(renderNames, renderOptions);
            return cuberille::apps::runRenderCommand(renderOptions);
        }
        if (app.got_subcommand("batch")) return cuberille::apps::runBatchCommand(batchOptions);
        if (app.got_subcommand("pack")) return cuberille::apps::runPackCommand(packOptions);
        if (app.got_subcommand("voxelize")) return cuberille::apps::runVoxelizeCommand(voxelizeOptions);
        if (app.got_subcommand("isosurface")) return cuberille::apps::runIsosurfaceCommand(isosurfaceOptions);
        if (app.got_subcommand("info")) return cuberille::apps::runInfoCommand(infoOptions);
        if (app.got_subcommand("fly")) return cuberille::apps::runFlyCommand(flyOptions);
        if (app.got_subcommand("explain")) return cuberille::apps::runExplainCommand(explainOptions);
        if (app.got_subcommand("accuracy")) return cuberille::apps::runAccuracyCommand(accuracyOptions);
    } catch (const cuberille::scene::InputError& e) {
        std::fprintf(stderr, "cuberille: %s\n", e.what());
        return kExitBadInput;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "cuberille: %s\n", e.what());
        return kExitFailure;
    }
    return 0;
}
