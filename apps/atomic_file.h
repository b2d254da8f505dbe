#pragma once
// Output files written under a temporary name in the same folder and renamed into place on
// commit (DESIGN.md, command line): a failure part-way, or an exception, leaves neither a torn
// file nor a clobbered earlier one, because the temporary is removed unless committed.

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

namespace cuberille::apps {

class AtomicOutputFile {
public:
    /// Throws std::runtime_error naming the file when the temporary cannot be created.
    explicit AtomicOutputFile(std::filesystem::path path);
    ~AtomicOutputFile();
    AtomicOutputFile(const AtomicOutputFile&) = delete;
    AtomicOutputFile& operator=(const AtomicOutputFile&) = delete;

    std::ofstream& stream() { return out_; }
    /// Flushes, checks and renames into place; throws std::runtime_error naming the file.
    void commit();

private:
    std::filesystem::path path_, temp_;
    std::ofstream out_;
    bool committed_ = false;
};

/// Refuses, before any work, an output path that could only fail at the end: one that names an
/// existing folder, or whose folder does not exist (a run writes all its outputs or none).
/// `option` names the option in the message (`--out`). Throws scene::InputError (exit code 2).
void requireOutputPath(const std::filesystem::path& path, const std::string& option);

/// `--stats` files: the JSON, indented, written atomically.
void writeJsonAtomically(const std::filesystem::path& path, const nlohmann::json& json);

}  // namespace cuberille::apps
