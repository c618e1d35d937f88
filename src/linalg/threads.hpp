#pragma once
/// \file Eigen's products on one thread while a scope lives. Loops of small dense products (a
/// reduced model's steps, a sweep's points: hundreds of rows) gain nothing from Eigen's OpenMP
/// threads, which spin-wait between the products: on a shared machine (load 9 on 2 cores) that made
/// the beam sweep 14x slower (43 s against 3 s for 52 points, docs/benchmarks.md section 7).
#include <Eigen/Core>

namespace crackle::linalg {

/// Sets Eigen's thread count to 1 for its lifetime and restores the previous count, also when the
/// scope is left by an exception (an interruption, a solver error).
class SingleThreadedEigen {
 public:
  SingleThreadedEigen() : threads_(Eigen::nbThreads()) { Eigen::setNbThreads(1); }
  ~SingleThreadedEigen() { Eigen::setNbThreads(threads_); }
  SingleThreadedEigen(const SingleThreadedEigen&) = delete;
  SingleThreadedEigen& operator=(const SingleThreadedEigen&) = delete;

 private:
  int threads_;
};

}  // namespace crackle::linalg
