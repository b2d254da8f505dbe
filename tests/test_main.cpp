// The test programs' main: GoogleTest's, run on the instruction set CUBERILLE_SIMD names
// (raster/instruction_set.h). tests/CMakeLists.txt runs the golden suite and the raster suites
// once per compiled set this way; a set this CPU cannot run is a skip, not a failure.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include "apps/worker_threads.h"
#include "raster/instruction_set.h"

namespace {

/// ctest's SKIP_RETURN_CODE for these runs (the automake convention).
constexpr int kExitSkipped = 77;

}  // namespace

int main(int argc, char** argv) {
    const cuberille::apps::WorkerThreadsJoinedAtExit workerThreads;  // first in, last out
    ::testing::InitGoogleTest(&argc, argv);
    try {
        cuberille::raster::useInstructionSetFromEnvironment();
    } catch (const std::invalid_argument& e) {
        const char* asked = std::getenv(cuberille::raster::kInstructionSetVariable);
        const auto compiled = cuberille::raster::compiledInstructionSets();
        if (std::find(compiled.begin(), compiled.end(), asked) != compiled.end()) {
            std::printf("skipped: %s\n", e.what());
            return kExitSkipped;
        }
        std::fprintf(stderr, "%s\n", e.what());
        return 1;
    }
    std::printf("instruction set: %s\n", cuberille::raster::activeInstructionSet().c_str());
    return RUN_ALL_TESTS();
}
