// The geometry flags that several subcommands share (energy, verify):
// --a, --alpha-deg, --d or --geometry FILE, and --theta-deg for the initial
// joint angles, registered once and read with the same checks and messages.
#pragma once

#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "geometry_input.hpp"
#include "loopfarm/core/loop.hpp"

namespace loopfarm::cli {

// The option texts exactly as given; read_geometry parses and checks them.
struct GeometryOptions {
  std::string a, alpha_deg, d, geometry, theta_deg;
  CLI::Option* a_option = nullptr;
  CLI::Option* alpha_option = nullptr;
  CLI::Option* d_option = nullptr;
  CLI::Option* geometry_option = nullptr;
  CLI::Option* theta_option = nullptr;
};

void add_geometry_options(CLI::App& app, GeometryOptions& options);

struct GeometryRequest {
  GeometryInput input;
  LoopGeometry geometry;
  std::optional<JointVector> theta;  // initial joint angles [rad], if given
  std::optional<double> theta0_deg;  // theta1 of --theta-deg as typed, if given
};

// Throws UsageError naming the flag (or file, line and key) for bad input.
GeometryRequest read_geometry(const GeometryOptions& options);

bool given(const CLI::Option* option);

}  // namespace loopfarm::cli
