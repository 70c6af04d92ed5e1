// Timing driver for HILBERT's C++ port (peer benchmark of issue 14; ours, not theirs).
// Usage: hilbert_driver PREFIX ETA REPEAT [DUMP]
//   PREFIX_coordinates.dat / PREFIX_elements.dat (1-based, HILBERT's format),
//   prints the minimum wall time in ms over REPEAT runs of computeV + computeK + computeW,
//   and with DUMP also writes PREFIX_{V,K,W}.bin (raw doubles, column major).
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <string>
#include <Eigen/Dense>
#include "BoundaryMesh.hpp"
#include "buildK.hpp"
#include "buildV.hpp"
#include "buildW.hpp"

static Eigen::MatrixXd read_matrix(const std::string& name, int cols) {
  std::ifstream in(name);
  std::vector<double> v; double x;
  while (in >> x) v.push_back(x);
  const int rows = static_cast<int>(v.size()) / cols;
  Eigen::MatrixXd m(rows, cols);
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j) m(i, j) = v[i * cols + j];
  return m;
}

static void dump(const std::string& name, const Eigen::MatrixXd& m) {
  std::ofstream out(name, std::ios::binary);
  out.write(reinterpret_cast<const char*>(m.data()), sizeof(double) * m.size());
}

int main(int argc, char** argv) {
  if (argc < 4) { std::fprintf(stderr, "usage: %s PREFIX ETA REPEAT [DUMP]\n", argv[0]); return 2; }
  const std::string prefix = argv[1];
  const double eta = std::atof(argv[2]);
  const int repeat = std::atoi(argv[3]);
  const Eigen::Matrix<double, Eigen::Dynamic, 2> coords = read_matrix(prefix + "_coordinates.dat", 2);
  const Eigen::Matrix<int, Eigen::Dynamic, 2> elems =
      (read_matrix(prefix + "_elements.dat", 2).array() - 1.0).cast<int>();
  BoundaryMesh mesh(coords, elems);
  Eigen::MatrixXd V, K, W;
  double best = std::numeric_limits<double>::infinity();
  for (int r = 0; r < repeat; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    computeV(V, mesh, eta);
    computeK(K, mesh, eta);
    computeW(W, mesh, eta);
    const auto t1 = std::chrono::steady_clock::now();
    best = std::min(best, std::chrono::duration<double, std::milli>(t1 - t0).count());
  }
  if (argc > 4) { dump(prefix + "_V.bin", V); dump(prefix + "_K.bin", K); dump(prefix + "_W.bin", W); }
  std::printf("%.6f\n", best);
  return 0;
}
