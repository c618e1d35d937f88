#pragma once
/// \file (internal) PETSc/SLEPc calls that throw crackle::SolverError instead of aborting.
///
/// PETSc reports an error by returning a non-zero code after its error handler ran; the default
/// handler prints a traceback. PetscErrorCapture replaces the handler by one that records the
/// innermost message, and CRACKLE_PETSC(call) turns a non-zero code into a SolverError carrying
/// the call, the message and the code. No path calls MPI_Abort.
#include <petscsys.h>

#include <string>

namespace crackle::modal::detail {

/// Installs the recording error handler for its lifetime (and resets the recorded message).
class PetscErrorCapture {
 public:
  PetscErrorCapture();
  ~PetscErrorCapture();
  PetscErrorCapture(const PetscErrorCapture&) = delete;
  PetscErrorCapture& operator=(const PetscErrorCapture&) = delete;
};

/// Throws SolverError if `code` is non-zero.
void check_petsc(PetscErrorCode code, const char* call, const char* context);

/// RAII owner of a PETSc object handle (Mat, Vec, EPS, VecScatter): destroys it on scope exit.
template <typename Handle, PetscErrorCode (*Destroy)(Handle*)>
class Owned {
 public:
  Owned() = default;
  ~Owned() {
    if (handle_) Destroy(&handle_);
  }
  Owned(const Owned&) = delete;
  Owned& operator=(const Owned&) = delete;
  Handle* address() { return &handle_; }
  operator Handle() const { return handle_; }  // NOLINT(google-explicit-constructor)

 private:
  Handle handle_ = nullptr;
};

}  // namespace crackle::modal::detail

/// Calls a PETSc/SLEPc function; a non-zero error code becomes crackle::SolverError.
#define CRACKLE_PETSC(context, call) ::crackle::modal::detail::check_petsc((call), #call, context)
