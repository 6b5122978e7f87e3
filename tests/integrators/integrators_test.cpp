#include <gtest/gtest.h>
TEST(Integrators, Placeholder) {}
