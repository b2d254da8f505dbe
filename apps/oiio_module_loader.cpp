#include "apps/oiio_module.h"

#include <dlfcn.h>

#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace cuberille::apps {
namespace {

/// Where the module may be, in order: beside the program (the build tree, and a portable
/// install), the installed layout's lib/cuberille, and where this build put it (so test and
/// benchmark programs in other folders of the build tree find it too).
std::vector<std::filesystem::path> moduleCandidates() {
    std::vector<std::filesystem::path> paths;
    std::error_code ec;
    const std::filesystem::path program = std::filesystem::read_symlink("/proc/self/exe", ec);
    if (!ec) {
        paths.push_back(program.parent_path() / kOiioModuleFileName);
        paths.push_back(program.parent_path().parent_path() / "lib" / "cuberille" / kOiioModuleFileName);
    }
#ifdef CUBERILLE_OIIO_MODULE_BUILD_PATH
    paths.push_back(CUBERILLE_OIIO_MODULE_BUILD_PATH);
#endif
    return paths;
}

const OiioModule& load() {
    std::string tried;
    for (const std::filesystem::path& path : moduleCandidates()) {
        std::error_code ec;
        if (!std::filesystem::exists(path, ec)) {
            tried += "\n  " + path.string() + " (absent)";
            continue;
        }
        // Never unloaded: the module's functions are used until the process ends.
        void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!handle) {
            tried += "\n  " + path.string() + " (" + dlerror() + ")";
            continue;
        }
        using Entry = const OiioModule* (*)();
        const auto entry = reinterpret_cast<Entry>(dlsym(handle, kOiioModuleEntryPoint));
        const OiioModule* module = entry ? entry() : nullptr;
        if (!module || module->interfaceVersion != OiioModule::kInterfaceVersion) {
            tried += "\n  " + path.string() + " (not this build's module)";
            continue;
        }
        return *module;
    }
    throw std::runtime_error("EXR files, image formats other than PNG and plots need the OpenImageIO module " +
                             std::string(kOiioModuleFileName) + ", which could not be loaded; tried:" + tried);
}

}  // namespace

const OiioModule& oiioModule() {
    static const OiioModule& module = load();  // a failed load throws, and the next call retries
    return module;
}

}  // namespace cuberille::apps
