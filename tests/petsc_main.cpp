/// \file GoogleTest main for tests that use PETSc/SLEPc: initialises SLEPc (and MPI) around the
/// tests, in a private MPI session folder. GoogleTest takes its flags first; PETSc gets the rest (and PETSC_OPTIONS).
#include <gtest/gtest.h>
#include <slepcsys.h>

#include "core/mpi_session.hpp"

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  // Its own MPI session folder: ctest starts several of these at once (core/mpi_session.hpp).
  const crackle::MpiSessionFolder session_folder;
  if (SlepcInitialize(&argc, &argv, nullptr, nullptr) != 0) return 1;
  const int result = RUN_ALL_TESTS();
  if (SlepcFinalize() != 0) return 1;
  return result;
}
