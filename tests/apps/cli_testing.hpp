#pragma once
/// \file Running the built `crackle` executable from the end-to-end tests.
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace cli_testing {

struct Result {
  int exit_code = -1;
  std::string output;  ///< stdout and stderr together
};

/// Runs `crackle ARGUMENTS` with an optional environment prefix ("A=1 B=2"), capturing its output.
inline Result crackle(const std::string& arguments, const std::string& environment = "") {
  const std::string command =
      environment + " " + std::string(CRACKLE_BINARY_DIR) + "/apps/crackle " + arguments + " 2>&1";
  Result result;
  FILE* pipe = popen(command.c_str(), "r");
  std::array<char, 4096> buffer;
  while (std::fgets(buffer.data(), buffer.size(), pipe)) result.output += buffer.data();
  const int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

/// A scene of the repository's data/ folder.
inline std::string data(const std::string& name) { return std::string(CRACKLE_SOURCE_DIR) + "/data/" + name; }

}  // namespace cli_testing
