#pragma once
// Bad input (a file, a value on the command line): the message names the file, the place in it
// and the problem. The tool maps it to exit code 2 (DESIGN.md, command line). Problems a reader
// recovers from go to a WarningSink instead.

#include <functional>
#include <stdexcept>
#include <string>

namespace cuberille::scene {

class InputError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// Where readers report problems they recover from (a missing texture, an unsupported
/// feature), each message naming the file.
using WarningSink = std::function<void(const std::string&)>;

}  // namespace cuberille::scene
