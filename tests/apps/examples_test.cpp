// The README's commands, run as written (issue 30: a new user follows the README literally).
// The example inputs are made by examples/make_examples.py into a fresh folder, the commands run
// from there with the README's `build/release/apps/cuberille` standing for the tool under test.

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tests/temp_paths.h"

namespace cuberille::testing {
namespace {

namespace fs = std::filesystem;

/// The commands of the README's "Using it" block: continuation lines joined, comments and
/// blank lines dropped.
std::vector<std::string> readmeCommands() {
    std::ifstream in(fs::path(CUBERILLE_SOURCE_DIR) / "README.md");
    std::stringstream text;
    text << in.rdbuf();
    const std::string s = text.str();
    const size_t section = s.find("## Using it");
    const size_t begin = s.find("```sh\n", section);
    const size_t end = s.find("```", begin + 6);
    if (section == std::string::npos || begin == std::string::npos || end == std::string::npos) return {};
    std::istringstream block(s.substr(begin + 6, end - begin - 6));
    std::vector<std::string> commands;
    std::string line, pending;
    while (std::getline(block, line)) {
        const bool continues = !line.empty() && line.back() == '\\';
        pending += continues ? line.substr(0, line.size() - 1) : line;
        if (continues) continue;
        const size_t first = pending.find_first_not_of(' ');
        if (first != std::string::npos && pending[first] != '#') commands.push_back(pending.substr(first));
        pending.clear();
    }
    return commands;
}

std::pair<int, std::string> runShell(const std::string& command) {
    FILE* pipe = popen((command + " 2>&1").c_str(), "r");
    std::string output;
    char buffer[512];
    while (pipe && fgets(buffer, sizeof buffer, pipe)) output += buffer;
    const int status = pipe ? pclose(pipe) : -1;
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

TEST(Examples, EveryReadmeCommandRunsAsWritten) {
    const std::vector<std::string> commands = readmeCommands();
    ASSERT_GE(commands.size(), 20u) << "the README's command block was not found or lost commands";
    const fs::path dir = uniqueTempPath("readme-examples");
    fs::remove_all(dir);
    fs::create_directories(dir);
    const auto [made, makeOutput] = runShell("python3 " + (fs::path(CUBERILLE_SOURCE_DIR) / "examples" / "make_examples.py").string() +
                                            " " + (dir / "examples").string());
    ASSERT_EQ(made, 0) << makeOutput;
    const std::string tool = "build/release/apps/cuberille";
    for (std::string command : commands) {
        ASSERT_EQ(command.rfind(tool, 0), 0u) << "not a cuberille command: " << command;
        command.replace(0, tool.size(), CUBERILLE_BINARY);
        const auto [exitCode, output] = runShell("cd " + dir.string() + " && " + command);
        EXPECT_EQ(exitCode, 0) << command << "\n" << output;
    }
    fs::remove_all(dir);
}

}  // namespace
}  // namespace cuberille::testing
