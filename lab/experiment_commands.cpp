// Placeholder until the experiment room registers its subcommands.
#include "lab/commands.hpp"

namespace weedspray::lab {
void add_experiment_commands(CLI::App& /*app*/) {}
}  // namespace weedspray::lab
