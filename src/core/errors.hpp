#pragma once
/// \file Typed exceptions for everything a user can cause (STYLE.md: two tiers of errors).
/// Programmer mistakes are debug asserts; these carry the offending values in the message.
#include <stdexcept>
#include <string>
#include <vector>

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

/// The shortest text that reads back as exactly `value` (std::to_chars): plot and table data,
/// where format_number's 15 digits would lose the last bits.
std::string shortest_text(double value);

/// The words joined by `separator`: join({"a", "b"}) is "a, b".
std::string join(const std::vector<std::string>& words, const std::string& separator = ", ");

/// The YAML text of a number list, each by format_number: "[0.2, 0.01, 4]".
std::string list_text(const std::vector<double>& values);

}  // namespace crackle
