#include "apps/atomic_file.h"

#include <unistd.h>

#include <stdexcept>

#include "scene/input_error.h"

namespace cuberille::apps {

AtomicOutputFile::AtomicOutputFile(std::filesystem::path path) : path_(std::move(path)) {
    const std::filesystem::path dir = path_.has_parent_path() ? path_.parent_path() : std::filesystem::path(".");
    temp_ = dir / ("." + path_.filename().string() + ".tmp" + std::to_string(::getpid()));
    out_.open(temp_, std::ios::binary | std::ios::trunc);
    if (!out_) throw std::runtime_error(path_.string() + ": cannot create the file");
}

AtomicOutputFile::~AtomicOutputFile() {
    if (committed_) return;
    out_.close();
    std::error_code ignored;
    std::filesystem::remove(temp_, ignored);
}

void AtomicOutputFile::commit() {
    out_.flush();
    const bool ok = bool(out_);
    out_.close();
    if (!ok || out_.fail()) throw std::runtime_error(path_.string() + ": write failed (disk full?)");
    std::error_code ec;
    std::filesystem::rename(temp_, path_, ec);
    if (ec) throw std::runtime_error(path_.string() + ": cannot rename the finished file into place: " + ec.message());
    committed_ = true;
}

void requireOutputPath(const std::filesystem::path& path, const std::string& option) {
    namespace fs = std::filesystem;
    if (path.empty()) return;
    std::error_code ec;
    if (fs::is_directory(path, ec))
        throw scene::InputError(option + " " + path.string() + ": is a folder; name a file in it");
    const fs::path folder = path.has_parent_path() ? path.parent_path() : fs::path(".");
    if (!fs::exists(folder, ec))
        throw scene::InputError(option + " " + path.string() + ": the folder " + folder.string() + " does not exist");
    if (!fs::is_directory(folder, ec))
        throw scene::InputError(option + " " + path.string() + ": " + folder.string() + " is not a folder");
}

void writeJsonAtomically(const std::filesystem::path& path, const nlohmann::json& json) {
    AtomicOutputFile f(path);
    f.stream() << json.dump(2) << "\n";
    f.commit();
}

}  // namespace cuberille::apps
