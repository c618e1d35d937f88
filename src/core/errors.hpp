#pragma once
/// \file Typed exceptions for everything a user can cause (STYLE.md: two tiers of errors).
/// Programmer mistakes are debug asserts; these carry the offending values in the message.
#include <stdexcept>
#include <string>

namespace crackle {

/// Base of all crackle errors; `main()` catches it and exits non-zero.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Bad input: scene files, option values, meshes. Exit code 2.
class InputError : public Error {
 public:
  using Error::Error;
};

/// A numerical solver failed (factorisation, eigen-solve, instability). Exit code 3.
class SolverError : public Error {
 public:
  using Error::Error;
};

/// Reading or writing a file failed. Exit code 4.
class IoError : public Error {
 public:
  using Error::Error;
};

/// Exit code that `main()` returns for an exception of this type.
int exit_code_for(const std::exception& error);

/// Formats a double the way messages show it: the shortest form with at most 15 significant
/// digits that reads back as the same value, else 15 digits ("2e+11" -> "2e11").
std::string format_number(double value);

}  // namespace crackle
