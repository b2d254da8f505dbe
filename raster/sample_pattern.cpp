#include "raster/sample_pattern.h"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace cuberille::raster {
namespace {

SamplePattern makePattern(std::initializer_list<std::pair<int, int>> offsets) {
    SamplePattern p;
    p.count = static_cast<int>(offsets.size());
    int i = 0;
    for (auto [x, y] : offsets) {
        p.dx[i] = static_cast<int8_t>(x);
        p.dy[i] = static_cast<int8_t>(y);
        ++i;
    }
    p.minDx = *std::min_element(p.dx.begin(), p.dx.begin() + p.count);
    p.maxDx = *std::max_element(p.dx.begin(), p.dx.begin() + p.count);
    p.minDy = *std::min_element(p.dy.begin(), p.dy.begin() + p.count);
    p.maxDy = *std::max_element(p.dy.begin(), p.dy.begin() + p.count);
    return p;
}

const SamplePattern kPattern1 = makePattern({{0, 0}});
const SamplePattern kPattern2 = makePattern({{4, 4}, {-4, -4}});
const SamplePattern kPattern4 = makePattern({{-2, -6}, {6, -2}, {-6, 2}, {2, 6}});
const SamplePattern kPattern8 =
    makePattern({{1, -3}, {-1, 3}, {5, 1}, {-3, -5}, {-5, 5}, {-7, -1}, {3, 7}, {7, -7}});
const SamplePattern kPattern16 =
    makePattern({{1, 1}, {-1, -3}, {-3, 2}, {4, -1}, {-5, -2}, {2, 5}, {5, 3}, {3, -5},
                 {-2, 6}, {0, -7}, {-4, -6}, {-6, 4}, {-8, 0}, {7, -4}, {6, 7}, {-7, -8}});

}  // namespace

bool isSupportedSampleCount(int count) {
    return count == 1 || count == 2 || count == 4 || count == 8 || count == 16;
}

const SamplePattern& standardSamplePattern(int count) {
    switch (count) {
        case 1: return kPattern1;
        case 2: return kPattern2;
        case 4: return kPattern4;
        case 8: return kPattern8;
        case 16: return kPattern16;
        default:
            throw std::invalid_argument("unsupported sample count " + std::to_string(count) +
                                        " (use 1, 2, 4, 8 or 16)");
    }
}

}  // namespace cuberille::raster
