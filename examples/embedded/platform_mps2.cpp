// platform.hpp on QEMU's mps2-an386: ARM semihosting (BKPT 0xAB, QEMU -semihosting-config
// enable=on,target=native) for the console and the exit code, the SysTick counter as the clock, and
// the counting malloc that --wrap puts in place of newlib's.

#include <cstddef>
#include <cstdint>

#include "platform.hpp"

namespace {

// A semihosting call: operation in r0, argument block in r1, result in r0.
std::uint32_t semihost(std::uint32_t operation, const void* argument) {
  register std::uint32_t r0 asm("r0") = operation;
  register const void* r1 asm("r1") = argument;
  asm volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
  return r0;
}

constexpr std::uint32_t kSysWrite0 = 0x04, kSysExit = 0x18;
constexpr std::uint32_t kApplicationExit = 0x20026, kRunTimeError = 0x20023;  // ADP_Stopped_*

// SysTick (ARMv7-M SCS): control/status, reload, current value.
volatile std::uint32_t& sysTickControl = *reinterpret_cast<volatile std::uint32_t*>(0xE000E010u);
volatile std::uint32_t& sysTickReload = *reinterpret_cast<volatile std::uint32_t*>(0xE000E014u);
volatile std::uint32_t& sysTickCurrent = *reinterpret_cast<volatile std::uint32_t*>(0xE000E018u);

constexpr std::uint32_t kPattern = 0xA5C3A5C3u;
std::uint32_t* paintedTop = nullptr;
std::uint32_t* paintedBottom = nullptr;
std::uint32_t heapCallCount = 0;

}  // namespace

namespace embedded {

const int tickBits = 24;

void writeText(const char* text) { semihost(kSysWrite0, text); }

[[noreturn]] void exitProgram(int code) {
  // The 32-bit SYS_EXIT takes the reason itself: QEMU exits 0 on ApplicationExit, 1 on any other.
  semihost(kSysExit, reinterpret_cast<const void*>(code == 0 ? kApplicationExit : kRunTimeError));
  for (;;) {
  }
}

// Counts down at the processor clock (CLKSOURCE = 1): returned negated so that it counts up.
std::uint32_t ticks() {
  if ((sysTickControl & 1u) == 0) {
    sysTickReload = 0xFFFFFFu;
    sysTickCurrent = 0;
    sysTickControl = 0x5u;  // ENABLE | CLKSOURCE, no interrupt
  }
  return (0u - sysTickCurrent) & 0xFFFFFFu;
}

std::uint32_t ticksOfLoop(std::uint32_t loops) {
  const std::uint32_t start = ticks();
  asm volatile("1:\n\tsubs %0, %0, #1\n\tbne 1b" : "+r"(loops) : : "cc");
  return (ticks() - start) & 0xFFFFFFu;
}

// A leaf that pushes nothing at -O2/-Os: its SP is the caller's.
void paintStack(std::uint32_t depth) {
  std::uint32_t* sp;
  asm volatile("mov %0, sp" : "=r"(sp));
  paintedTop = sp;
  paintedBottom = sp - depth / 4;
  for (std::uint32_t* p = paintedBottom; p < paintedTop; ++p) *p = kPattern;
}

std::uint32_t stackUsedSincePaint() {
  std::uint32_t* p = paintedBottom;
  while (p < paintedTop && *p == kPattern) ++p;
  return static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(paintedTop) - reinterpret_cast<std::uintptr_t>(p));
}

std::uint32_t heapCalls() { return heapCallCount; }

}  // namespace embedded

// The firmware is linked with --wrap=malloc,calloc,realloc,_malloc_r: a call from anywhere lands here,
// is counted, and fails (returns null): the example does not provide a heap, so nothing is forwarded,
// and __real_malloc is never referenced (it would link newlib's allocator in).
extern "C" {
void* __wrap_malloc(std::size_t) { return ++heapCallCount, nullptr; }
void* __wrap_calloc(std::size_t, std::size_t) { return ++heapCallCount, nullptr; }
void* __wrap_realloc(void*, std::size_t) { return ++heapCallCount, nullptr; }
void* __wrap__malloc_r(void*, std::size_t) { return ++heapCallCount, nullptr; }
}
