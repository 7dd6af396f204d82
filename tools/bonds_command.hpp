// `loopfarm bonds`: the polynomial relations between every pair of joint
// angles along a loop's traced motion and their fingerprint
// (include/loopfarm/search/bond_relations.hpp), for one geometry given as
// `loopfarm verify` takes it, or for the candidates of a results database,
// grouped into classes by equal fingerprint. Read-only, except with --store,
// which writes the fingerprints measured into the database in one
// transaction.
#pragma once

#include "subcommand.hpp"

namespace loopfarm::cli {

Subcommand add_bonds_command(CLI::App& parent);

}  // namespace loopfarm::cli
