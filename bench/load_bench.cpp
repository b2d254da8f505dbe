// Mesh reading against memory speed: each file's bytes are read once, then parsed (PLY or OBJ)
// and, as the peer, copied with memcpy, each several times; the table gives the medians and the
// parse's multiple of the copy. A reader "near memory speed" is a small multiple of it.
//
//   load_bench [--files dragon,horse,bunny,PATH...] [--repeat N]
//
// `dragon` is the Stanford dragon's binary PLY (decompressed in memory first, so the parse is
// measured, not zlib), `dragon-ascii` its ASCII PLY, `horse` the Cyberware horse's binary PLY,
// `bunny` the Stanford bunny's OBJ.

#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "bench/bench_support.h"
#include "scene/file_names.h"
#include "scene/obj_loader.h"
#include "scene/ply_loader.h"

namespace {

using namespace cuberille;
namespace fs = std::filesystem;

double nowMs() {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

fs::path fileFor(const std::string& name) {
    const fs::path scans = fs::path(CUBERILLE_SOURCE_DIR) / ".." / "shared" / "data" / "scans";
    if (name == "dragon-ascii") return scans / "stanford-dragon" / "dragon_vrip.ply.gz";
    return bench::scanPath(name, CUBERILLE_SOURCE_DIR);
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app("Mesh reading (PLY, OBJ) against memcpy of the same bytes");
    std::string files = "dragon,dragon-ascii,horse,bunny";
    int repeat = 7;
    app.add_option("--files", files, "Comma-separated scans or paths")->capture_default_str();
    app.add_option("--repeat", repeat, "Timed runs per file; the median is printed")->capture_default_str();
    CLI11_PARSE(app, argc, argv);

    std::printf("| file | MB | triangles | read file ms | parse ms | memcpy ms | parse / memcpy |\n");
    std::printf("|---|---:|---:|---:|---:|---:|---:|\n");
    for (const std::string& name : bench::splitList(files)) {
        const fs::path path = fileFor(name);
        if (!fs::exists(path)) {
            std::printf("| %s | skipped: %s is absent | | | | | |\n", name.c_str(), path.c_str());
            continue;
        }
        double t0 = nowMs();
        const std::string bytes = scene::readFileBytes(path);
        const double readMs = nowMs() - t0;
        const bool isObj = scene::fileKindOf(path) == scene::FileKind::Obj;
        std::vector<double> parse, copy;
        size_t triangles = 0;
        std::string target(bytes.size(), '\0');
        for (int r = 0; r < repeat; ++r) {
            t0 = nowMs();
            if (isObj) {
                const auto meshes = scene::parseObj(bytes, path.string(), path.parent_path(), [](const std::string&) {});
                triangles = 0;
                for (const scene::Mesh& m : meshes) triangles += m.triangleCount();
            } else {
                triangles = scene::parsePly(bytes, path.string()).triangleCount();
            }
            parse.push_back(nowMs() - t0);
            t0 = nowMs();
            std::memcpy(target.data(), bytes.data(), bytes.size());
            copy.push_back(nowMs() - t0);
            if (target[target.size() / 2] != bytes[bytes.size() / 2]) return 1;  // keep the copy
        }
        const double p = bench::median(parse), c = bench::median(copy);
        std::printf("| %s | %.1f | %zu | %.1f | %.1f | %.2f | %.0fx |\n", name.c_str(), double(bytes.size()) / 1e6,
                    triangles, readMs, p, c, p / c);
    }
    return 0;
}
