// Built in the sanitizer build only (build/sanitize): checks that the build's sanitizers are
// compiled in and that each kind of report ends the process with a failure, so that a report in
// any other test fails `make test` (scripts/sanitizer_tests.sh runs them with halt_on_error).
// If the flags were lost from CMakeLists.txt, or a report only printed and let the test carry
// on, these death tests would see a process that did not die, and fail.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <limits>
#include <memory>

namespace {

// volatile: the compiler must neither drop a fault whose result is unused nor fold it away.
int ReadPastTheEnd(int elements) {
  std::unique_ptr<int[]> values(new int[static_cast<std::size_t>(elements)]());
  volatile int index = elements;
  volatile int read = values[static_cast<std::size_t>(index)];
  return read;
}

int UseAfterFree() {
  int* value = new int(7);
  delete value;
  volatile int* dangling = value;
  volatile int read = *dangling;
  return read;
}

std::int32_t AddOverflowing(std::int32_t a) {
  volatile std::int32_t b = 1;
  volatile std::int32_t sum = a + b;  // signed overflow for INT32_MAX: undefined behaviour
  return sum;
}

int ShiftTooFar(int bits) {
  volatile int one = 1;
  volatile int shifted = one << bits;
  return shifted;
}

// Not inlined: no copy of the pointer may stay in the caller's registers or stack, where
// LeakSanitizer would find it and call the block reachable.
__attribute__((noinline)) void Leak() {
  volatile int* leaked = new int[64];
  leaked[0] = 1;
}

void LeakAndExit() {
  Leak();
  std::exit(0);  // LeakSanitizer looks at exit; a leak turns the exit status into a failure
}

TEST(SanitizerReports, AddressSanitizerStopsAHeapBufferOverflow) {
  EXPECT_DEATH(ReadPastTheEnd(4), "AddressSanitizer: heap-buffer-overflow");
}

TEST(SanitizerReports, AddressSanitizerStopsAUseAfterFree) {
  EXPECT_DEATH(UseAfterFree(), "AddressSanitizer: heap-use-after-free");
}

TEST(SanitizerReports, UndefinedBehaviorSanitizerStopsASignedOverflow) {
  EXPECT_DEATH(AddOverflowing(std::numeric_limits<std::int32_t>::max()),
               "runtime error: signed integer overflow");
}

TEST(SanitizerReports, UndefinedBehaviorSanitizerStopsAShiftPastTheWidth) {
  EXPECT_DEATH(ShiftTooFar(40), "runtime error: shift exponent 40");
}

TEST(SanitizerReports, LeakSanitizerFailsAnExitThatLeaks) {
  EXPECT_EXIT(
      LeakAndExit(), [](int status) { return !testing::ExitedWithCode(0)(status); },
      "LeakSanitizer: detected memory leaks");
}

}  // namespace
