// `study_cli SCENE -o DIR --exe CRACKLE [--jobs N] [--no-modal-cache] [--retry-failed]`: runs a
// study the way `crackle study` does (the lead's app wiring calls the same run_study), so that
// tests can kill it, interrupt it, or start it as MPI ranks.
#include <cstdlib>
#include <iostream>
#include <string>

#include "core/errors.hpp"
#include "study/study.hpp"

int main(int argc, char** argv) {
  crackle::study::StudyOptions options;
  for (int i = 1; i < argc; ++i) {
    const std::string argument = argv[i];
    const auto next = [&]() -> std::string { return i + 1 < argc ? argv[++i] : ""; };
    if (argument == "-o")
      options.output_dir = next();
    else if (argument == "--exe")
      options.executable = next();
    else if (argument == "--jobs")
      options.jobs = std::atoi(next().c_str());
    else if (argument == "--no-modal-cache")
      options.modal_cache = false;
    else if (argument == "--retry-failed")
      options.retry_failed = true;
    else
      options.scene_path = argument;
  }
  try {
    return crackle::study::run_study(options, std::cerr);
  } catch (const std::exception& error) {
    std::cerr << "crackle: error: " << error.what() << "\n";
    return crackle::exit_code_for(error);
  }
}
