#pragma once
// Little-endian binary records for the voxel file formats (.cgs, .cvox). Every read is bounds-
// checked against what the file holds, so a truncated or corrupted file becomes an InputError
// naming the file, the byte offset and the field, never an out-of-bounds read.

#include <fcntl.h>
#include <unistd.h>

#include <bit>
#include <cerrno>
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

/// A file read with positional reads (pread): any number of threads may read it at once, which
/// is how geometry-stream chunks and voxel blocks are loaded on demand.
class PositionalFile {
public:
    /// Throws scene::InputError naming the file when it cannot be opened.
    explicit PositionalFile(std::string name) : name_(std::move(name)) {
        fd_ = ::open(name_.c_str(), O_RDONLY | O_CLOEXEC);
        if (fd_ < 0) throw scene::InputError(name_ + ": cannot open: " + std::strerror(errno));
        bytes_ = uint64_t(::lseek(fd_, 0, SEEK_END));
    }
    ~PositionalFile() { ::close(fd_); }
    PositionalFile(const PositionalFile&) = delete;
    PositionalFile& operator=(const PositionalFile&) = delete;

    const std::string& name() const { return name_; }
    uint64_t size() const { return bytes_; }

    /// Exactly n bytes at offset, or scene::InputError naming `where` and the offset.
    void readAt(uint64_t offset, char* out, size_t n, const std::string& where) const {
        size_t done = 0;
        while (done < n) {
            const ssize_t got = ::pread(fd_, out + done, n - done, off_t(offset + done));
            if (got <= 0)
                throw scene::InputError(where + " at byte " + std::to_string(offset + done) + ": " +
                                        (got == 0 ? "truncated: unexpected end of file" : std::strerror(errno)));
            done += size_t(got);
        }
    }

private:
    std::string name_;
    int fd_ = -1;
    uint64_t bytes_ = 0;
};

}  // namespace cuberille::voxel
