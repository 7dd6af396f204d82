// What makes two runs' jobs the same job for `loopfarm merge`: their text as
// TOML, the [output] table left out (each slice of an array may write to a
// node-local path of its own, and report_threshold only decides which starts
// keep their geometry). Private to the store.
#pragma once

#include <string>
#include <string_view>

namespace loopfarm::store {

// The job's TOML without its [output] table, written out again by toml++:
// comments, layout and the order of keys do not matter, values and tables do.
// Throws std::invalid_argument (naming `source_name`) when the text is not TOML.
std::string merge_identity(std::string_view job_text, const std::string& source_name);

// The first line where two identities differ, as "`A` against `B`" (a line
// missing on one side is "(nothing)"), prefixed by the table it is in.
std::string first_difference(const std::string& x, const std::string& y);

}  // namespace loopfarm::store
