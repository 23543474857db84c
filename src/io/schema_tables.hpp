#pragma once
// The schema of the input in parts (private to src/io/): config.cpp declares the root, the model
// and time-stepping tables and calls the parts below, in the order docs/input.md lists them.
#include "mpmcd/io/schema.hpp"

namespace mpmcd::io {

/// Adds the tables of the interaction and of the run's control to `s`, in order: [contact],
/// [[contact.pairs]], [[walls]], [loading] and its stages, [stop], [output], [checkpoint]
/// (config_interaction.cpp).
void add_interaction_tables(Schema& s);

}  // namespace mpmcd::io
