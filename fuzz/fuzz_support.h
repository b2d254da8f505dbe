#pragma once
// Shared by the fuzz targets: each feeds libFuzzer's bytes to one reader, the way the tool reads a
// file, and accepts exactly one kind of failure — scene::InputError, the clear message naming the
// file and place. Anything else (a crash, a sanitizer report, another exception, an allocation
// the limits should have refused, a hang) is a finding.

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <unistd.h>

#include "scene/input_error.h"

namespace cuberille::fuzz {

/// The input as a file with the given extension (readers take paths), removed afterwards.
class InputFile {
public:
    InputFile(const uint8_t* data, size_t size, const std::string& extension)
        : path_(std::filesystem::temp_directory_path() /
                ("cuberille-fuzz-" + std::to_string(::getpid()) + extension)) {
        std::ofstream(path_, std::ios::binary).write(reinterpret_cast<const char*>(data), std::streamsize(size));
    }
    ~InputFile() { std::filesystem::remove(path_); }
    const std::filesystem::path& path() const { return path_; }

private:
    std::filesystem::path path_;
};

/// Runs the reader; an InputError is the expected way to refuse bad input.
template <typename Read>
void acceptingInputErrors(Read&& read) {
    try {
        read();
    } catch (const scene::InputError&) {
    }
}

inline std::string_view bytesOf(const uint8_t* data, size_t size) {
    return {reinterpret_cast<const char*>(data), size};
}

inline void ignoreWarning(const std::string&) {}

}  // namespace cuberille::fuzz
