// How `loopfarm verify` and `loopfarm motion` show the rigid loop's
// circuits: readable lines, JSON, and CSV of the input-output curves.
// Joints are numbered from 1 and angles are in degrees, as everywhere users
// read them.
#pragma once

#include <cstdio>
#include <string>

#include <nlohmann/json.hpp>

#include "loopfarm/core/motion.hpp"

namespace loopfarm::cli {

// Indented lines, one block per circuit; `reported` is marked.
void print_circuits(const MotionAnalysis& motion, int input_joint, int reported);

// [{...}, ...]: one object per circuit (see docs/guide/motion.md for the keys).
nlohmann::ordered_json circuits_json(const MotionAnalysis& motion, int input_joint);

// One row a point: circuit, point, arclength_rad, then theta1_deg ...
// thetan_deg (the input is theta of the input joint), with a header row.
void write_circuits_csv(const MotionAnalysis& motion, std::FILE* out);

}  // namespace loopfarm::cli
