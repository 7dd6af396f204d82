// The rocking joint of the zero-offset 5R search's near-misses
// (docs/research/discovery-5r-6r.md, "The rocking joint: near-misses of a locked-joint
// Bennett loop"). Not part of the build; a measurement kept as documentation.
//
// Replays start INDEX of JOB, takes its least-travelling joint k (locked at 0
// or pi in these loops), projects the final geometry x0 onto the locked-joint
// Bennett loops (the 4R left by locking k, with the fused link a_{k-1} +- a_k,
// alpha_{k-1} +- alpha_k, Bennett; minimum-norm Gauss-Newton on the five
// conditions in the job's free parameters) giving x_L, and for
// x_t = x_L + t (x0 - x_L) prints: the locked 4R's Bennett distance, E_mean
// (unsteered), the rigid walk's worst residual and joint k's travel, and
// classify's answer. With a third argument: the walk at t = 1 and 10 with
// 720 ... 720,000 steps per turn.
//
//   cmake --build build --target loopfarm
//   g++ -O2 -std=c++20 -Iinclude -isystem /usr/include/eigen3 docs/research/rocking_joint_scaling.cpp \
//       build/libloopfarm.a -lnlopt -ltomlplusplus -lsqlite3 -o /tmp/rocking
//   /tmp/rocking jobs/discovery/zero-offsets-5r.toml 945 [fine]
#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include "loopfarm/search/classify.hpp"
#include "loopfarm/search/job.hpp"
#include "loopfarm/search/local_dimension.hpp"
#include "loopfarm/search/objective.hpp"
#include "loopfarm/search/start.hpp"
using namespace loopfarm;
Job job;
int K;
double S;
LoopGeometry four_r(const LoopGeometry& g0) {
  LoopGeometry g = scaled(g0, length_scale(g0));
  LoopGeometry w = relabelled(g, K + 1);
  LoopGeometry r;
  r.a.resize(4);
  r.alpha.resize(4);
  r.d = JointVector::Zero(4);
  for (int j = 0; j < 3; ++j) {
    r.a[j] = w.a[j];
    r.alpha[j] = w.alpha[j];
  }
  double ac = w.a[3] + S * w.a[4], al = w.alpha[3] + S * w.alpha[4];
  if (ac < 0) {
    ac = -ac;
    al = -al;
  }
  r.a[3] = ac;
  r.alpha[3] = wrap_angle(al);
  return r;
}
int choice[3] = {-1, -1, -1};
double twist_rel(double a, double b, int c) {
  switch (c) {
    case 0:
      return wrap_angle(a - b);
    case 1:
      return wrap_angle(a - b - M_PI);
    case 2:
      return wrap_angle(a + b);
    default:
      return wrap_angle(a + b - M_PI);
  }
}
Eigen::VectorXd cond(const Eigen::VectorXd& x) {
  LoopGeometry r = four_r(job.space.geometry(x));
  if (choice[0] < 0) {
    for (int p = 0; p < 2; ++p) {
      double best = 1e9;
      for (int c = 0; c < 4; ++c) {
        double v = std::abs(twist_rel(r.alpha[p], r.alpha[p + 2], c));
        if (v < best) {
          best = v;
          choice[p] = c;
        }
      }
    }
    choice[2] = std::abs(r.a[0] * std::sin(r.alpha[1]) - r.a[1] * std::sin(r.alpha[0])) <
                        std::abs(r.a[0] * std::sin(r.alpha[1]) + r.a[1] * std::sin(r.alpha[0]))
                    ? 0
                    : 1;
  }
  Eigen::VectorXd v(5);
  v << r.a[0] - r.a[2], r.a[1] - r.a[3], twist_rel(r.alpha[0], r.alpha[2], choice[0]),
      twist_rel(r.alpha[1], r.alpha[3], choice[1]),
      r.a[0] * std::sin(r.alpha[1]) + (choice[2] ? 1 : -1) * r.a[1] * std::sin(r.alpha[0]);
  return v;
}
int main(int argc, char** argv) {
  job = read_job_file(argv[1]);
  long idx = std::atol(argv[2]);
  StartSummary s = run_start(job, idx);
  const auto& v = s.candidate.verification;
  int n = 5;
  K = 0;
  for (int j = 0; j < n; ++j)
    if (v.joint_travel[j] < v.joint_travel[K]) K = j;
  S = std::cos(s.final_angles[K]) > 0 ? 1.0 : -1.0;
  Eigen::VectorXd x0 = job.space.free_values(s.final_geometry);
  Eigen::VectorXd x = x0;
  std::printf("start %ld joint %d locked at %s; bennett distance of the locked 4R at start %.2e\n", idx, K + 1,
              S > 0 ? "0" : "pi", family_distance(Family::bennett, four_r(s.final_geometry)));
  for (int it = 0; it < 20; ++it) {  // minimum-norm Gauss-Newton onto the conditions
    Eigen::VectorXd c = cond(x);
    Eigen::MatrixXd J(c.size(), x.size());
    for (int j = 0; j < x.size(); ++j) {
      Eigen::VectorXd xp = x, xm = x;
      double h = 1e-7 * std::max(1.0, std::abs(x[j]));
      xp[j] += h;
      xm[j] -= h;
      J.col(j) = (cond(xp) - cond(xm)) / (2 * h);
    }
    Eigen::VectorXd step = J.completeOrthogonalDecomposition().solve(-c);
    x += step;
    if (step.norm() < 1e-16) break;
  }
  std::printf("projected: distance %.2e, |x - x_L| = %.2e\n",
              family_distance(Family::bennett, four_r(job.space.geometry(x))), (x0 - x).norm());
  Eigen::VectorXd xL = x;
  {
    Eigen::VectorXd dx = x0 - xL;
    std::printf("x (search labels, a1..a5 then alpha1..alpha5 [rad]):");
    for (int j = 0; j < x.size(); ++j) std::printf(" %.5f", x0[j]);
    std::printf("\ndx/|dx|:");
    for (int j = 0; j < x.size(); ++j) std::printf(" %+.3f", dx[j] / dx.norm());
    std::printf("\n");
  }
  ObjectiveOptions plain = ObjectiveOptions::from_loop(job.loop);
  plain.measure = CycleMeasure::mean;
  // The singular values of the cycle's deformation Jacobian (local_dimension's
  // input, lengths times L) at the search's point and at its projection.
  std::vector<bool> is_length;
  for (int index : job.space.free_indices()) {
    const int kind = index / job.space.joints;
    is_length.push_back(kind == static_cast<int>(ParameterKind::a) || kind == static_cast<int>(ParameterKind::d));
  }
  for (const Eigen::VectorXd* at : {&x0, &xL}) {
    CycleObjective obj(job.space, plain, s.final_angles);
    Eigen::VectorXd r;
    Eigen::MatrixXd J;
    obj.evaluate_residuals(*at, r, &J);
    const LocalDimension ld =
        local_dimension(dimensionless_columns(J, is_length, length_scale(job.space.geometry(*at))));
    std::printf("%s: local dimension %d, singular values", at == &x0 ? "search's point" : "projection", ld.dimension);
    for (int j = 0; j < ld.singular_values.size(); ++j) std::printf(" %.2g", ld.singular_values[j]);
    std::printf("\n");
  }
  std::printf("%8s %10s %10s %10s %10s %10s %8s %s\n", "t", "|dx|", "bennett", "E_mean", "worst_res", "travel_k",
              "verified", "family");
  if (argc > 3) {
    for (double t : {1.0, 10.0})
      for (int steps : {720, 7200, 72000, 720000}) {
        Eigen::VectorXd xt = xL + t * (x0 - xL);
        LoopGeometry g = job.space.geometry(xt);
        CycleObjective obj(job.space, plain, s.final_angles);
        obj.evaluate(xt, nullptr);
        VerificationOptions vo;
        vo.steps_per_turn = steps;
        VerificationSummary vs = verify_motion(g, obj.start_state().theta, vo);
        std::printf("t %g steps %d: verified %d full %d worst %.2e travel_k %.2e %s\n", t, steps, vs.verified,
                    vs.full_turn, vs.worst_residual, vs.joint_travel[K], vs.limit.c_str());
      }
    return 0;
  }
  for (double t : {0.0, 0.01, 0.1, 0.3, 1.0, 3.0, 10.0, 30.0, 100.0, 1000.0}) {
    Eigen::VectorXd xt = xL + t * (x0 - xL);
    LoopGeometry g = job.space.geometry(xt);
    CycleObjective obj(job.space, plain, s.final_angles);
    ObjectiveValue val = obj.evaluate(xt, nullptr);
    JointVector pose = obj.start_state().theta;
    VerificationSummary vs = verify_motion(g, pose);
    std::vector<double> tr(vs.joint_travel.data(), vs.joint_travel.data() + vs.joint_travel.size());
    Classification cl = classify(g, pose, vs.verified ? std::span<const double>(tr) : std::span<const double>());
    std::printf("%8g %10.2e %10.2e %10.2e %10.2e %10.2e %8d %s (%s)\n", t, (xt - xL).norm(),
                family_distance(Family::bennett, four_r(g)), val.ok ? val.E_mean : NAN, vs.worst_residual,
                vs.verified ? vs.joint_travel[K] : NAN, vs.verified, to_string(cl.family), cl.detail.c_str());
  }
}
