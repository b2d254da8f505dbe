#pragma once
// Where tests write their files: under the system's temporary folder, named for the process, so
// that two runs at once (two presets, two clones, ctest's parallel processes) never share a file
// and the working tree is left as the test found it.

#include <filesystem>
#include <mutex>
#include <string>
#include <system_error>
#include <vector>

#include <unistd.h>

namespace cuberille::testing {

namespace detail {

/// Every path handed out, removed (with whatever was put under it) when the test process exits,
/// so a test that forgets to clean up, or fails before it can, leaves nothing in the temporary
/// folder (only a crash does). Removing what a test already removed is a no-op.
struct TempPathRegistry {
    std::mutex mutex;
    std::vector<std::filesystem::path> paths;
    ~TempPathRegistry() {
        for (const std::filesystem::path& p : paths) {
            std::error_code ignored;
            std::filesystem::remove_all(p, ignored);
        }
    }
};

inline TempPathRegistry& tempPathRegistry() {
    static TempPathRegistry registry;
    return registry;
}

}  // namespace detail

/// temp/cuberille-<pid>-<name>: unique to this process; the caller creates it, and it is removed
/// when the process exits (the caller may remove it sooner).
inline std::filesystem::path uniqueTempPath(const std::string& name) {
    std::filesystem::path p = std::filesystem::temp_directory_path() / ("cuberille-" + std::to_string(::getpid()) + "-" + name);
    detail::TempPathRegistry& registry = detail::tempPathRegistry();
    const std::lock_guard lock(registry.mutex);
    registry.paths.push_back(p);
    return p;
}

}  // namespace cuberille::testing
