#pragma once
/// \file The subcommands of the `crackle` executable, callable from tests.
#include <iosfwd>
#include <string>

namespace crackle::app {

struct CheckOptions {
  std::string scene_path;
  bool assemble = true;  ///< assemble K and the lumped M to report mass and assembly time
};

/// `crackle check`: validates a scene and prints a summary (nodes, elements, DOFs, crack pairs,
/// total mass, assembly time). Throws InputError on a bad scene.
void run_check(const CheckOptions& options, std::ostream& out);

}  // namespace crackle::app
