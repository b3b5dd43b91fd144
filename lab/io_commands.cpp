// Placeholder until the io room registers its subcommands.
#include "lab/commands.hpp"

namespace weedspray::lab {
void add_io_commands(CLI::App& /*app*/) {}
}  // namespace weedspray::lab
