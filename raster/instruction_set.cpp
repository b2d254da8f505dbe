#include "raster/instruction_set.h"

#include <cctype>
#include <cstdlib>
#include <stdexcept>

#include <hwy/targets.h>

namespace cuberille::raster {
namespace {

std::string nameOf(int64_t target) {
    switch (target) {
#if HWY_ARCH_X86
        case HWY_AVX3: return "avx512";
        case HWY_AVX2: return "avx2";
#endif
        default: break;
    }
    if (target == HWY_STATIC_TARGET) return "baseline";
    std::string name = hwy::TargetName(target);
    for (char& c : name) c = char(std::tolower(static_cast<unsigned char>(c)));
    return name;
}

/// Targets compiled into the back end (HWY_TARGETS: this library is built with the same
/// HWY_DISABLED_TARGETS as tile_raster.cpp) that the CPU runs. Asked once, before any
/// restriction: restrictions are made only by useInstructionSet(), which asks first.
int64_t compiledAndSupported() {
    static const int64_t targets = hwy::SupportedTargets() & HWY_TARGETS;
    return targets;
}

int64_t lowestBit(int64_t targets) { return targets & -targets; }

/// Names of a set of targets, widest first (Highway numbers better targets with lower bits).
std::vector<std::string> namesOf(int64_t targets) {
    std::vector<std::string> names;
    for (int64_t rest = targets; rest != 0; rest &= rest - 1) names.push_back(nameOf(lowestBit(rest)));
    return names;
}

std::string joined(const std::vector<std::string>& names) {
    std::string out;
    for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
    return out;
}

}  // namespace

std::vector<std::string> availableInstructionSets() { return namesOf(compiledAndSupported()); }

std::vector<std::string> compiledInstructionSets() { return namesOf(HWY_TARGETS); }

std::string activeInstructionSet() { return nameOf(lowestBit(hwy::SupportedTargets() & HWY_TARGETS)); }

void useInstructionSet(std::string_view name) {
    const int64_t all = compiledAndSupported();
    if (name == "best" || name.empty()) return hwy::DisableTargets(0);
    for (int64_t rest = all; rest != 0; rest &= rest - 1) {
        const int64_t target = lowestBit(rest);
        // Disabling every better target (the lower bits) leaves this one the best, and makes
        // the next HWY_DYNAMIC_DISPATCH choose it.
        if (nameOf(target) == name) return hwy::DisableTargets(target - 1);
    }
    const std::vector<std::string> names = availableInstructionSets();
    for (const std::string& compiled : compiledInstructionSets())
        if (compiled == name)
            throw std::invalid_argument("this CPU does not support the instruction set '" + std::string(name) +
                                        "'; it runs best, " + joined(names));
    throw std::invalid_argument("unknown instruction set '" + std::string(name) +
                                "': this build on this CPU runs best, " + joined(names));
}

void useInstructionSetFromEnvironment() {
    const char* value = std::getenv(kInstructionSetVariable);
    if (!value || !*value) return;
    try {
        useInstructionSet(value);
    } catch (const std::invalid_argument& e) {
        throw std::invalid_argument(std::string(kInstructionSetVariable) + ": " + e.what());
    }
}

}  // namespace cuberille::raster
