// Whole processes side by side: `cuberille render FILE --out x.png` against llvmpipe_render (the
// same file read by the same loaders, drawn by Mesa's llvmpipe, written as PNG), started
// alternately, each timed from spawn to exit: start-up, load, render and write together.
// What a user who renders one image per process pays (docs/performance.md).

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "bench/bench_support.h"

extern char** environ;

namespace {

/// Wall milliseconds from spawn to exit; -1 when the process fails.
double timeProcess(const std::vector<std::string>& args) {
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);  // the summary lines
    const auto t0 = std::chrono::steady_clock::now();
    pid_t pid;
    if (posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ) != 0) return -1;
    int status = 0;
    waitpid(pid, &status, 0);
    posix_spawn_file_actions_destroy(&actions);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return WIFEXITED(status) && WEXITSTATUS(status) == 0 ? ms : -1;
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"Whole-process time against llvmpipe: start-up, load, render, write"};
    std::string files, msaaList = "1,4", size = "640x480,1920x1080";
    int runs = 7;
    app.add_option("--files", files, "Comma-separated model files (.gltf .glb .ply .obj)")->required();
    app.add_option("--msaa", msaaList, "Comma-separated sample counts");
    app.add_option("--sizes", size, "Comma-separated WIDTHxHEIGHT");
    app.add_option("--runs", runs, "Processes of each kind per row (median reported)");
    CLI11_PARSE(app, argc, argv);
    const std::string dir = std::filesystem::path(argv[0]).parent_path().string();
    const std::string cuberille = dir + "/../apps/cuberille", peer = dir + "/llvmpipe_render";
    const std::string out = (std::filesystem::temp_directory_path() / "process_bench.png").string();
    std::printf("# whole processes, median of %d each, started alternately; threads: all cores for both\n", runs);
    std::printf("%-28s %10s %4s | %10s | %10s | %6s\n", "file", "size", "msaa", "cuberille", "llvmpipe", "ratio");
    for (const std::string& file : cuberille::bench::splitList(files)) {
        for (const std::string& wh : cuberille::bench::splitList(size)) {
            const std::string w = wh.substr(0, wh.find('x')), h = wh.substr(wh.find('x') + 1);
            for (const std::string& msaa : cuberille::bench::splitList(msaaList)) {
                std::vector<double> ours, theirs;
                for (int r = 0; r < runs; ++r) {
                    ours.push_back(timeProcess({cuberille, "render", file, "--width", w, "--height", h, "--msaa", msaa, "--out", out}));
                    theirs.push_back(timeProcess({peer, file, "--width", w, "--height", h, "--msaa", msaa, "--out", out}));
                }
                if (*std::min_element(ours.begin(), ours.end()) < 0 || *std::min_element(theirs.begin(), theirs.end()) < 0) {
                    std::printf("%-28s %10s %4s | a process failed\n", std::filesystem::path(file).filename().c_str(), wh.c_str(), msaa.c_str());
                    continue;
                }
                const double a = median(ours), b = median(theirs);
                std::printf("%-28s %10s %4s | %8.0f ms | %8.0f ms | %5.2fx\n", std::filesystem::path(file).filename().c_str(),
                            wh.c_str(), msaa.c_str(), a, b, b / a);
            }
        }
    }
    return 0;
}
