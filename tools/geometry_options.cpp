#include "geometry_options.hpp"

#include <vector>

#include "cli_support.hpp"

namespace loopfarm::cli {
namespace {
constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;
}  // namespace

bool given(const CLI::Option* option) { return option != nullptr && option->count() > 0; }

void add_geometry_options(CLI::App& app, GeometryOptions& o) {
  o.a_option = app.add_option("--a", o.a, "link lengths a1,...,an (4 <= n <= 8), each >= 0")->type_name("LIST");
  o.alpha_option = app.add_option("--alpha-deg", o.alpha_deg, "link twists alpha1,...,alphan [deg]")->type_name("LIST");
  o.d_option = app.add_option("--d", o.d, "joint offsets d1,...,dn (default: all 0)")->type_name("LIST");
  o.geometry_option =
      app.add_option("--geometry", o.geometry,
                     "TOML file with arrays a, alpha_deg and optionally d, instead of --a/--alpha-deg/--d")
          ->type_name("FILE");
  o.geometry_option->excludes(o.a_option)->excludes(o.alpha_option)->excludes(o.d_option);
  o.theta_option =
      app.add_option("--theta-deg", o.theta_deg,
                     "initial joint angles theta1,...,thetan [deg]: theta1 is theta0, the others the passive "
                     "angles' starting guess (default: the loop is assembled automatically)")
          ->type_name("LIST");
}

GeometryRequest read_geometry(const GeometryOptions& o) {
  GeometryRequest request;
  if (given(o.geometry_option)) {
    request.input = geometry_from_toml(o.geometry);
  } else {
    if (!given(o.a_option)) {
      throw UsageError("--a",
                       "missing: give the link lengths with --a and the twists with --alpha-deg "
                       "(e.g. --a 2,4,2,4 --alpha-deg 30,90,30,90), or --geometry FILE.toml");
    }
    if (!given(o.alpha_option)) {
      throw UsageError("--alpha-deg", "missing: give the twists in degrees, e.g. --alpha-deg 30,90,30,90");
    }
    request.input =
        geometry_from_flags(o.a, o.alpha_deg, given(o.d_option) ? std::optional<std::string>(o.d) : std::nullopt);
  }
  request.geometry = make_geometry(request.input);
  const int n = request.geometry.joints();
  if (given(o.theta_option)) {
    const std::vector<double> theta_deg = parse_number_list(o.theta_deg, "--theta-deg");
    if (theta_deg.size() != static_cast<size_t>(n)) {
      throw UsageError("--theta-deg", std::to_string(theta_deg.size()) + " values (" + format_list(theta_deg) +
                                          ") but " + request.input.a.source + " has " + std::to_string(n) +
                                          "; give one initial angle per joint, the input joint first");
    }
    JointVector theta(n);
    for (int i = 0; i < n; ++i) theta[i] = theta_deg[static_cast<size_t>(i)] / kDegreesPerRadian;
    request.theta = theta;
    request.theta0_deg = theta_deg.front();
  }
  return request;
}

}  // namespace loopfarm::cli
