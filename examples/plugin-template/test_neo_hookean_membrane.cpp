// The law's stress is the derivative of its energy (SDK finite-difference
// checker), at a few deformations; exits non-zero on failure.
#include <cstdio>

#include <thermostamp/sdk/fd_check.hpp>

namespace neo_hookean {
ts::sdk::MaterialLaw* create();
}

int main() {
  ts::sdk::MaterialLaw* law = neo_hookean::create();
  ts::sdk::Params p;
  ts::sdk::Params::Value mu, lambda;
  mu.real = 1.0e4;
  lambda.real = 2.0e4;
  p.set("mu", mu);
  p.set("lambda", lambda);
  if (!law->configure(p)) return 1;
  const ts::sdk::Sym2 cases[] = {{1.2, 0.9, 0.1}, {1.05, 1.0, 0.0}, {0.8, 1.5, -0.3}, {2.0, 0.6, 0.4}};
  int failed = 0;
  for (const auto& C : cases) {
    const auto r = ts::sdk::fd_check(*law, C, 20.0);
    std::printf("C = [%g, %g, %g]: relative error %.2e\n", C[0], C[1], C[2], r.max_relative_error);
    if (r.max_relative_error > 1e-6) ++failed;
  }
  delete law;
  std::printf("%d passed, %d failed\n", 4 - failed, failed);
  return failed ? 1 : 0;
}
