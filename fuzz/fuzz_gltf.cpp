// glTF 2.0, .gltf and .glb (scene/gltf_loader.h, scene/model_scene.h): tinygltf parses, and our
// side — node hierarchy, accessors against their buffers, skins, morph targets, animation, the
// scene's framing — must refuse what does not fit with an InputError.
#include "fuzz/fuzz_support.h"
#include "scene/model_scene.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace cuberille;
    const bool binary = size >= 4 && std::string_view(reinterpret_cast<const char*>(data), 4) == "glTF";
    const fuzz::InputFile file(data, size, binary ? ".glb" : ".gltf");
    fuzz::acceptingInputErrors([&] {
        scene::ModelSceneOptions view;
        view.timeSeconds = 0.5f;
        scene::loadModelScene(file.path(), view, fuzz::ignoreWarning);
    });
    return 0;
}
