#include "scene/tri_scene.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "scene/input_error.h"
#include "scene/text_parsing.h"

namespace cuberille::scene {
namespace {

[[noreturn]] void fail(const std::string& file, size_t line, const std::string& problem) {
    throw InputError(file + ":" + std::to_string(line) + ": " + problem);
}

std::vector<float> parseNumbers(std::string_view text, const std::string& file, size_t line) {
    std::vector<float> numbers;
    for (std::string_view token : splitWords(text)) {
        float value = 0;
        const char* first = token.data();
        if (token[0] == '+') ++first;  // from_chars rejects a leading '+'
        auto [end, ec] = std::from_chars(first, token.data() + token.size(), value);
        if (ec != std::errc() || end != token.data() + token.size())
            fail(file, line, "'" + std::string(token) + "' is not a number");
        if (!std::isfinite(value)) fail(file, line, "'" + std::string(token) + "' is not a finite number");
        numbers.push_back(value);
    }
    return numbers;
}

}  // namespace

raster::DrawCall TriScene::drawCall() const {
    raster::DrawCall draw;
    draw.space = raster::PositionSpace::Window;
    draw.positions = positions;
    draw.triangleColors = colors;
    draw.state.shading = raster::ShadingModel::ConstantColor;
    draw.state.depthTest = false;
    draw.state.depthWrite = false;
    draw.state.cull = raster::CullMode::None;
    return draw;
}

TriScene parseTriScene(const std::string& text, const std::string& fileName) {
    TriScene scene;
    size_t lineNumber = 0;
    size_t start = 0;
    while (start <= text.size()) {
        size_t end = text.find('\n', start);
        if (end == std::string::npos) end = text.size();
        ++lineNumber;
        std::string_view line(text.data() + start, end - start);
        if (const size_t hash = line.find('#'); hash != std::string_view::npos)
            line = line.substr(0, hash);
        const std::vector<float> n = parseNumbers(line, fileName, lineNumber);
        if (!n.empty()) {
            if (n.size() != 7 && n.size() != 9)
                fail(fileName, lineNumber,
                     "expected 7 numbers (x0 y0 x1 y1 x2 y2 v) or 9 (... r g b), found " +
                         std::to_string(n.size()));
            for (int v = 0; v < 3; ++v) scene.positions.emplace_back(n[2 * v], n[2 * v + 1], 0.0f);
            scene.colors.push_back(n.size() == 7 ? glm::vec4(n[6], n[6], n[6], 1.0f)
                                                 : glm::vec4(n[6], n[7], n[8], 1.0f));
        }
        if (end == text.size()) break;
        start = end + 1;
    }
    return scene;
}

TriScene loadTriScene(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path.string() + ": cannot open file");
    std::ostringstream buffer;
    buffer << in.rdbuf();
    return parseTriScene(buffer.str(), path.string());
}

}  // namespace cuberille::scene
