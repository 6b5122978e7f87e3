// platform.hpp on the host: stdout and the exit status; no clock, stack or heap figures (0).

#include <cstdio>
#include <cstdlib>

#include "platform.hpp"

namespace embedded {

const int tickBits = 24;

void writeText(const char* text) { std::fputs(text, stdout); }
[[noreturn]] void exitProgram(int code) {
  std::fflush(stdout);
  std::exit(code);
}
std::uint32_t ticks() { return 0; }
std::uint32_t ticksOfLoop(std::uint32_t) { return 0; }
void paintStack(std::uint32_t) {}
std::uint32_t stackUsedSincePaint() { return 0; }
std::uint32_t heapCalls() { return 0; }

}  // namespace embedded

int main() { return embedded::programMain(); }
