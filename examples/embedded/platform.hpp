#pragma once

// What the firmware example needs from the machine it runs on, implemented twice: by semihosting on
// the Cortex-M4F (platform_mps2.cpp, under QEMU's mps2-an386) and by the C library on the host
// (platform_host.cpp). Nothing here allocates.

#include <cstdint>

namespace embedded {

// The program (robot_filters.cpp): called by main() on the host, by the reset handler on the target
// (ISO C++ does not let a program call main itself). Returns the exit status.
int programMain();

// Writes a NUL-terminated text to the console (semihosting SYS_WRITE0 / stdout).
void writeText(const char* text);
// Ends the program with `code` (0: success).
[[noreturn]] void exitProgram(int code);

// A free-running clock for the instruction counts: ticks since an arbitrary origin, wrapping modulo
// 2^tickBits. On the target, the SysTick counter at the processor clock (25 MHz on mps2-an386: under
// QEMU -icount shift=0, one instruction is 1 ns, so 40 instructions a tick; docs/embedded.md); on the
// host, always 0 (no figure).
std::uint32_t ticks();
extern const int tickBits;
// The ticks of a loop of 2 · loops instructions (subs, bne), the scale of ticks() in instructions.
std::uint32_t ticksOfLoop(std::uint32_t loops);

// Stack high-water mark of a call: paintStack() fills the `depth` bytes of stack below the caller's
// frame with a pattern, stackUsedSincePaint() returns how many of them were overwritten since (0 on
// the host, where it is not measured).
void paintStack(std::uint32_t depth);
std::uint32_t stackUsedSincePaint();

// Calls to malloc/calloc/realloc (and newlib's _malloc_r) counted by the linker's --wrap (0 on the host).
std::uint32_t heapCalls();

}  // namespace embedded
