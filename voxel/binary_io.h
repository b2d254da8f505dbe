#pragma once
// Little-endian binary records for the voxel file formats (.cgs, .cvox). Every read is bounds-
// checked against what the file holds, so a truncated or corrupted file becomes an InputError
// naming the file, the byte offset and the field, never an out-of-bounds read.

#include <bit>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "scene/input_error.h"

namespace cuberille::voxel {

static_assert(std::endian::native == std::endian::little,
              "the voxel file formats are little-endian and written with memcpy");

class ByteWriter {
public:
    template <class T>
    void put(const T& value) {
        static_assert(std::is_trivially_copyable_v<T>);
        bytes_.append(reinterpret_cast<const char*>(&value), sizeof(T));
    }
    template <class T>
    void putArray(const T* values, size_t count) {
        static_assert(std::is_trivially_copyable_v<T>);
        if (count) bytes_.append(reinterpret_cast<const char*>(values), sizeof(T) * count);
    }
    void padTo(size_t alignment) {
        while (bytes_.size() % alignment) bytes_.push_back('\0');
    }
    size_t size() const { return bytes_.size(); }
    std::string& bytes() { return bytes_; }

private:
    std::string bytes_;  // (a std::vector<char> here trips GCC 12's -Wstringop-overflow falsely)
};

class ByteReader {
public:
    /// `where` names the file (and record) in messages; baseOffset is the position of bytes[0]
    /// in the file, so messages give file offsets.
    ByteReader(std::string_view bytes, std::string where, uint64_t baseOffset = 0)
        : bytes_(bytes), where_(std::move(where)), base_(baseOffset) {}

    template <class T>
    T get(const char* field) {
        static_assert(std::is_trivially_copyable_v<T>);
        require(sizeof(T), field);
        T value;
        std::memcpy(&value, bytes_.data() + at_, sizeof(T));
        at_ += sizeof(T);
        return value;
    }
    template <class T>
    void getArray(T* out, size_t count, const char* field) {
        static_assert(std::is_trivially_copyable_v<T>);
        if (count > (bytes_.size() - at_) / sizeof(T)) fail(field, "truncated: needs " + std::to_string(count) +
                                                                      " values, " + std::to_string(remaining()) +
                                                                      " bytes remain");
        if (count) std::memcpy(out, bytes_.data() + at_, sizeof(T) * count);
        at_ += sizeof(T) * count;
    }
    void skip(size_t n, const char* field) {
        require(n, field);
        at_ += n;
    }
    void alignTo(size_t alignment, const char* field) {
        const size_t pad = (alignment - (at_ % alignment)) % alignment;
        skip(pad, field);
    }
    size_t remaining() const { return bytes_.size() - at_; }
    uint64_t fileOffset() const { return base_ + at_; }

    [[noreturn]] void fail(const char* field, const std::string& problem) const {
        throw scene::InputError(where_ + " at byte " + std::to_string(fileOffset()) + " (" + field + "): " + problem);
    }

private:
    void require(size_t n, const char* field) const {
        if (n > remaining())
            fail(field, "truncated: needs " + std::to_string(n) + " bytes, " + std::to_string(remaining()) + " remain");
    }

    std::string_view bytes_;
    std::string where_;
    uint64_t base_;
    size_t at_ = 0;
};

}  // namespace cuberille::voxel
