#pragma once
// The installed library's version (libcuberille.so; CMake's project version), for a program
// that wants to report what it runs on.

namespace cuberille {

/// "MAJOR.MINOR.PATCH". Defined in libcuberille.so only, not in the static libraries.
const char* libraryVersion();

}  // namespace cuberille
