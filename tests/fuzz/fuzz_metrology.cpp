// libFuzzer entry point of the metrology target: sl::fuzz::metrologyInput in FuzzTargets.h says
// what it reads and checks. sl::InputError is the reader's documented refusal; anything else is a
// finding.
#include <cstdint>

#include "FuzzTargets.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    sl::fuzz::initialize();
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    try {
        sl::fuzz::feed(sl::fuzz::Target::Metrology, data, size);
    } catch (const sl::InputError&) {
    }
    return 0;
}
