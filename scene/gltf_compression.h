#pragma once
// glTF's compressed geometry, undone before the reader sees it: EXT_meshopt_compression's buffer
// views and KHR_draco_mesh_compression's primitives decoded into buffers of their own, so every
// accessor reads them as plain data.
//
// The extension's files carry a "fallback" buffer with no data (glTF 2.0 allows a buffer without
// a uri only as a GLB's BIN chunk; tinygltf refuses one anywhere else), so the JSON is adjusted
// first: each such buffer gets a data URI of four zero bytes (tinygltf refuses an empty one). A view still reading it
// afterwards (one the decoder did not replace) fails the reader's range check, naming the view.

#include <string>

namespace tinygltf {
class Model;
}

namespace cuberille::scene {

/// Whether a glTF's JSON may need parseableByTinygltf (a byte search, no parse: most files name
/// neither compression extension).
bool mentionsCompression(const std::string& json);

/// The JSON with what tinygltf refuses in compressed files made parseable: every
/// EXT_meshopt_compression fallback buffer (see above), and every KHR_draco_mesh_compression
/// primitive's index accessor without a buffer view (tinygltf requires one for indices) given the
/// primitive's compressed view, which the decoder then replaces. Any other JSON (one that does
/// not parse too: tinygltf names its error) is returned as it is.
std::string parseableByTinygltf(const std::string& json);

/// Whether a GLB's header and first chunk hold together: a JSON chunk inside the length the header
/// gives, the header's length inside the file. Only then do the two functions below apply
/// (otherwise tinygltf refuses the container, naming the problem).
bool hasJsonChunk(const std::string& glb);

/// A GLB's bytes with its JSON chunk replaced by `json` (padded with spaces to 4 bytes, lengths
/// rewritten); the chunks after it, up to the header's length, kept.
std::string glbWithJson(const std::string& glb, const std::string& json);

/// The JSON chunk of a GLB.
std::string glbJson(const std::string& glb);

/// Decodes every buffer view with EXT_meshopt_compression (modes ATTRIBUTES, TRIANGLES and
/// INDICES; filters NONE, OCTAHEDRAL, QUATERNION and EXPONENTIAL) into a buffer appended to the
/// model, and points the view at it. Throws InputError naming `file` and the view when the
/// compressed data is out of range or does not decode.
void decodeMeshoptBufferViews(tinygltf::Model& model, const std::string& file);

/// Decodes every primitive with KHR_draco_mesh_compression by Debian's Draco: its triangles into
/// its index accessor, each attribute the extension names (by Draco's unique id) into that
/// attribute's accessor, converted to the accessor's component type, each in a buffer appended to
/// the model. Throws InputError naming `file` and the primitive when the data does not decode or
/// does not fit its accessors.
void decodeDracoPrimitives(tinygltf::Model& model, const std::string& file);

}  // namespace cuberille::scene
