// Placeholder until the vision room registers its subcommands.
#include "lab/commands.hpp"

namespace weedspray::lab {
void add_vision_commands(CLI::App& /*app*/) {}
}  // namespace weedspray::lab
