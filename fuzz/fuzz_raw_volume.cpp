// Raw volumes with their dimensions, through `cuberille isosurface`'s own path: the first 8 bytes
// give the dimensions (3 x uint16, each at most 48 here, for speed), the sample type and the
// iso-value's byte; the rest is the file. A size that does not match the dimensions is an
// InputError naming the file.
#include <cstring>

#include "apps/voxel_commands.h"
#include "fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace cuberille;
    if (size < 8) return 0;
    uint16_t dims[3];
    std::memcpy(dims, data, 6);
    apps::IsosurfaceCommandOptions o;
    for (int k = 0; k < 3; ++k) o.dims[size_t(k)] = dims[k] % 49;
    o.type = data[6] % 3 == 0 ? "u8" : data[6] % 3 == 1 ? "u16" : "f32";
    o.iso = double(data[7]) / 4.0;
    const fuzz::InputFile volume(data + 8, size - 8, ".raw");
    o.volume = volume.path();
    o.out = volume.path().string() + ".cvox";
    o.threads = 1;
    o.quiet = true;
    fuzz::acceptingInputErrors([&] { apps::runIsosurfaceCommand(o); });
    std::filesystem::remove(o.out);
    return 0;
}
