/// \file The `crackle` executable: `crackle check|modal|... scene.yaml`.
#include <CLI/CLI.hpp>
#include <iostream>

#include "commands.hpp"
#include "core/errors.hpp"
#include "scene/scene.hpp"

int main(int argc, char** argv) {
  using namespace crackle;
  CLI::App cli{"crackle: nonlinear vibration of elastic bodies with a breathing crack"};
  cli.require_subcommand(1);
  cli.set_version_flag("--version", "crackle 0.1.0");

  app::CheckOptions check;
  CLI::App* check_command = cli.add_subcommand(
      "check", "Validate a scene, mesh it, assemble K and the lumped mass, and print a summary");
  check_command->add_option("scene", check.scene_path, "Scene file (YAML)")->required();
  check_command->add_flag("!--no-assembly", check.assemble, "Skip assembling K and M");

  CLI::App* format_command =
      cli.add_subcommand("scene-format", "Print the reference of every scene key (Markdown)");

  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    return cli.exit(error);
  }
  try {
    if (*check_command) app::run_check(check, std::cout);
    if (*format_command) std::cout << scene::scene_format_markdown();
  } catch (const std::exception& error) {
    std::cerr << "crackle: error: " << error.what() << "\n";
    return exit_code_for(error);
  }
  return 0;
}
