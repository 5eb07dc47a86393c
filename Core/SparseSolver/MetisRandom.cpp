#include "SparseSolver/MetisRandom.h"

#include <cstdint>
#include <cstdlib>
#include <dlfcn.h>

namespace {

// glibc's rand() is random() on a 128-byte (TYPE_3) state; random_r on a state of the same size,
// seeded the same way, gives the same sequence.
struct ThreadRandom {
  random_data data{};
  char state[128] = {};
  bool initialised = false;
  unsigned long long draws = 0;

  void seed(unsigned int value) {
    if (!initialised) {
      initstate_r(value, state, sizeof state, &data);
      initialised = true;
    } else {
      srandom_r(value, &data);
    }
  }
  uint32_t next() {
    if (!initialised)
      seed(1); // rand() without srand() starts as after srand(1)
    int32_t value = 0;
    random_r(&data, &value);
    ++draws;
    return static_cast<uint32_t>(value);
  }
};

thread_local ThreadRandom threadRandom;

} // namespace

// GKlib's random-number entry points (gk_macros / random.c), as libmetis.so.5 exports and calls
// them. Default visibility so that they are in the dynamic symbol table wherever Core is linked.
extern "C" {

__attribute__((visibility("default"))) void gk_randinit(uint64_t seed) {
  threadRandom.seed(static_cast<unsigned int>(seed)); // srand() takes the low 32 bits
}

__attribute__((visibility("default"))) uint32_t gk_randint32(void) { return threadRandom.next(); }

__attribute__((visibility("default"))) uint64_t gk_randint64(void) {
  const uint64_t high = threadRandom.next();
  const uint64_t low = threadRandom.next();
  return (high << 32) | low;
}

} // extern "C"

namespace faceplan {

unsigned long long MetisRandomDrawsOnThisThread() { return threadRandom.draws; }

bool MetisRandomIsPerThread() {
  static const bool perThread = [] {
    // libmetis as the process already has it (CHOLMOD loads it); not loaded here otherwise.
    void* metis = dlopen("libmetis.so.5", RTLD_LAZY | RTLD_NOLOAD);
    if (!metis)
      return false;
    using Draw = int (*)(void);
    auto irand = reinterpret_cast<Draw>(dlsym(metis, "libmetis__irand"));
    bool reached = false;
    if (irand) {
      const unsigned long long before = MetisRandomDrawsOnThisThread();
      irand(); // METIS's own function: its draw goes through libmetis's PLT
      reached = MetisRandomDrawsOnThisThread() == before + 1;
    }
    dlclose(metis);
    return reached;
  }();
  return perThread;
}

} // namespace faceplan
