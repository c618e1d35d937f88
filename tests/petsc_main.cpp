/// \file GoogleTest main for tests that use PETSc/SLEPc: initialises SLEPc (and MPI) around the
/// tests. GoogleTest takes its flags first; PETSc gets the rest (and PETSC_OPTIONS).
#include <gtest/gtest.h>
#include <slepcsys.h>

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  if (SlepcInitialize(&argc, &argv, nullptr, nullptr) != 0) return 1;
  const int result = RUN_ALL_TESTS();
  if (SlepcFinalize() != 0) return 1;
  return result;
}
