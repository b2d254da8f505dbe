#pragma once
// Where tests write their files: under the system's temporary folder, named for the process, so
// that two runs at once (two presets, two clones, ctest's parallel processes) never share a file
// and the working tree is left as the test found it.

#include <filesystem>
#include <string>

#include <unistd.h>

namespace cuberille::testing {

/// temp/cuberille-<pid>-<name>: unique to this process; the caller creates and removes it.
inline std::filesystem::path uniqueTempPath(const std::string& name) {
    return std::filesystem::temp_directory_path() / ("cuberille-" + std::to_string(::getpid()) + "-" + name);
}

}  // namespace cuberille::testing
