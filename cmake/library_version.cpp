// The one source of libcuberille.so's own (cmake/CMakeLists.txt); the rest comes whole from the
// renderer's archives.
#include "render/library_version.h"

namespace cuberille {

const char* libraryVersion() { return CUBERILLE_VERSION; }

}  // namespace cuberille
