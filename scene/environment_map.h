#pragma once
// Environments for image-based lighting (raster/environment_light.h), by the name the command
// line and the library take (`--environment`, FrameSettings::environment): `neutral`, the
// built-in studio, or an equirectangular radiance map in a file. Radiance HDR files (`.hdr`,
// RGBE, run-length encoded or flat) are read here; other formats, OpenEXR's among them, through a reader the
// embedding program registers (the command line registers its OpenImageIO module's, which is
// loaded only by a run that reads such a file).
//
// Preparing an environment (filtering its levels) takes a tenth of a second or so, so each is
// prepared once per process and kept: every frame, view and scene that names it shares it.

#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "raster/environment_light.h"

namespace cuberille::scene {

/// An equirectangular map as read from a file: linear RGB float triples, row-major, row 0 at
/// the top (EnvironmentLight::fromEquirectangular's layout).
struct EquirectangularImage {
    int width = 0, height = 0;
    std::vector<float> rgb;
};

/// Reads a radiance map of a format this library does not read itself; throws InputError
/// naming the file when it cannot.
using EnvironmentImageReader = std::function<EquirectangularImage(const std::filesystem::path&)>;

/// Registers the reader for files whose extension (lower case, with its dot: ".exr") the library
/// does not read itself. Not thread-safe against loadEnvironment: register before rendering.
void registerEnvironmentReader(const std::string& extension, EnvironmentImageReader reader);

/// Reads an equirectangular radiance map (.hdr here, other extensions through their registered
/// reader). Throws InputError naming the file for a missing, unreadable or malformed file, an
/// extension without a reader, and a map that is not twice as wide as it is high (within a
/// texel: equirectangular maps span 360 by 180 degrees).
EquirectangularImage readEquirectangularImage(const std::filesystem::path& path);

/// The environment `name` names (`neutral` or a file's path) scaled by `intensity`, prepared on
/// first use and kept for the rest of the process (a file again if it has changed on disk).
/// Throws InputError as readEquirectangularImage does, and for an intensity that is negative or
/// not finite.
std::shared_ptr<const raster::EnvironmentLight> loadEnvironment(const std::string& name, float intensity = 1.0f);

}  // namespace cuberille::scene
