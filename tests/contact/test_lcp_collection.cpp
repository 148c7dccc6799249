// The LCP problem collections of data/lcp against the solvers:
// the Siconos test collection with the outcome its README tabulates, and every
// rigid-body contact LCP (including the degenerate friction ones) solved.
#include <doctest/doctest.h>

#include <filesystem>
#include <optional>
#include <utility>

#include "contact/lcp/fallback.hpp"
#include "contact/lcp/lemke.hpp"
#include "contact/lcp/siconos_io.hpp"
#include "tests/contact/lcp_checks.hpp"

namespace floesim::lcp {
namespace {

TEST_SUITE_BEGIN("contact");

using testing::check_complementary;
using testing::lcp_data;
using testing::read_guess;

struct Expected {
  const char* file;
  Status status;
  long pivots;  // for a solve; the README's count for a lexicographic Lemke
};

// data/lcp/README.md, table "siconos/".
constexpr Expected kSiconos[] = {
    {"lcp_CPS_1", Status::solved, 2},
    {"lcp_CPS_2", Status::solved, 5},
    {"lcp_CPS_3", Status::ray, 0},  // copositive, not copositive-plus: secondary ray
    {"lcp_CPS_4", Status::solved, 5},
    {"lcp_CPS_4bis", Status::solved, 5},
    {"lcp_CPS_5", Status::solved, 2},
    {"lcp_Pang_isolated_sol", Status::solved, 3},
    {"lcp_Pang_isolated_sol_perturbed", Status::ray, 0},  // infeasible
    {"lcp_inf_sol_perturbed", Status::solved, 5},
    {"lcp_deudeu", Status::solved, 3},
    {"lcp_deudeu_block", Status::solved, 3},
    {"lcp_ortiz", Status::solved, 3},
    {"lcp_ortiz_block", Status::solved, 3},
    {"lcp_trivial", Status::solved, 10},
    {"lcp_trivial_block", Status::solved, 10},
    {"lcp_enum_fails", Status::solved, 8},
    {"lcp_exp_murty", Status::solved, 2},
    {"lcp_exp_murty2", Status::solved, 64},  // Murty's exponential example: 2^6
    {"lcp_mmc", Status::solved, 23},
    {"lcp_tobenna", Status::solved, 127},
};

TEST_CASE("lcp: every Siconos collection problem has its tabulated outcome") {
  // Dense LU, then each sparse LU forced on every basis.
  for (const auto& [f, lu] : {std::pair{Factorization::dense, SparseLu::umfpack},
                              std::pair{Factorization::sparse, SparseLu::umfpack},
                              std::pair{Factorization::sparse, SparseLu::klu}}) {
    for (const Expected& e : kSiconos) {
      const std::string file = e.file;
      CAPTURE(file);
      const std::string factorization = f == Factorization::dense ? "dense"
                                        : lu == SparseLu::klu     ? "klu"
                                                                  : "umfpack";
      CAPTURE(factorization);
      const Lcp lcp = read_siconos_lcp(lcp_data(std::string("siconos/") + e.file + ".dat"));
      LemkeOptions options;
      options.factorization = f;
      options.sparse_lu = lu;
      const Result r = solve_lemke(lcp, options);
      CHECK(to_string(r.status) == to_string(e.status));
      if (e.status == Status::solved) {
        CHECK(r.residual <= 1e-10);
        CHECK(r.pivots == e.pivots);
        check_complementary(lcp, r.z, 1e-10);
      }
    }
  }
}

TEST_CASE("lcp: the block-stored files hold the same LCP as their dense twins") {
  for (const char* name : {"lcp_deudeu", "lcp_ortiz", "lcp_trivial"}) {
    CAPTURE(name);
    const Lcp dense = read_siconos_lcp(lcp_data(std::string("siconos/") + name + ".dat"));
    const Lcp block = read_siconos_lcp(lcp_data(std::string("siconos/") + name + "_block.dat"));
    REQUIRE(block.is_sparse());
    REQUIRE_FALSE(dense.is_sparse());
    CHECK((DenseMatrix(std::get<SparseMatrix>(block.M)) - std::get<DenseMatrix>(dense.M)).norm() ==
          0.0);
    CHECK((block.q - dense.q).norm() == 0.0);
  }
}

TEST_CASE("lcp: Murty's matrix is read column-major (upper triangular)") {
  const Lcp lcp = read_siconos_lcp(lcp_data("siconos/lcp_exp_murty.dat"));
  const auto& M = std::get<DenseMatrix>(lcp.M);
  CHECK(M(0, 5) == 2.0);
  CHECK(M(5, 0) == 0.0);
  CHECK(M.isUpperTriangular());
}

TEST_CASE("lcp: the secondary rays are genuine (the fallback chain cannot solve them either)") {
  // Pang's perturbed problem is infeasible: every step of the chain must fail.
  const Lcp lcp = read_siconos_lcp(lcp_data("siconos/lcp_Pang_isolated_sol_perturbed.dat"));
  const FallbackResult r = solve_with_fallbacks(lcp);
  CHECK_FALSE(r.solved());
  CHECK(r.attempts.size() == 4);
  CHECK(r.attempts.front().status == Status::ray);
}

std::vector<std::string> contact_files() {
  std::vector<std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(lcp_data("contact")))
    if (entry.path().extension() == ".dat") files.push_back(entry.path().string());
  std::sort(files.begin(), files.end());
  return files;
}

TEST_CASE("lcp: every rigid-body contact LCP is solved - friction ones included") {
  const auto files = contact_files();
  REQUIRE(files.size() >= 20);
  for (const std::string& file : files) {
    CAPTURE(file);
    const Lcp lcp = read_siconos_lcp(file);
    LemkeStats stats;
    const Result r = solve_lemke(lcp, {}, &stats);
    CHECK(r.status == Status::solved);
    CHECK(r.residual <= 1e-9);
    check_complementary(lcp, r.z, 1e-9);
    MESSAGE(std::filesystem::path(file).filename().string() << ": n " << lcp.size() << ", pivots "
            << r.pivots << ", residual " << r.residual << ", tie-breaks " << stats.tie_breaks
            << ", solves " << stats.solves << ", UMFPACK refactorisations " << stats.sparse_refactorisations << " of "
            << stats.refactorisations);
  }
}

// Lemke's pivot path on the contact and jam LCPs of data/lcp, as walked by
// the revised method at 7c57e26 (before the pivot's work was cut down:
// covered rows by rows of A(W, S), etas in one block, no refactorisation of
// an unchanged basis, no allocation per pivot). That work must not change a
// single rounding: a jam's LCP is so degenerate that a tie decided otherwise
// walks another path. So the same pivots, the same number of basis solves
// (the tie-breaks' included) and the same end. The path was recorded with
// UMFPACK as the sparse LU and the default refactor_interval of 100; both are
// set here, as another LU rounds otherwise (the KLU test below).
struct Path {
  const char* file;
  bool warm;  // from NAME.guess
  Status status;
  long pivots;
  long solves;
};
constexpr Path kPaths[] = {
    {"contact/delassus_m200_s1", false, Status::solved, 92, 93},
    {"contact/delassus_red_m200_s1", false, Status::solved, 112, 114},
    {"contact/friction_m100_s2", false, Status::solved, 293, 370},
    {"contact/friction_m200_s1", false, Status::solved, 555, 665},
    {"contact/friction_m200_s2", false, Status::solved, 549, 649},
    {"jam/jam500_n1400", false, Status::solved, 1257, 1270},
    {"jam/jam500_n1400", true, Status::solved, 1125, 1139},
    {"jam/jam500_n2396", false, Status::solved, 1802, 2059},
    {"jam/jam500_n2396", true, Status::solved, 1195, 5878},
    {"jam/jam500_n864_ray", false, Status::solved, 602, 609},
    {"jam/jam500_n864_ray", true, Status::ray, 2, 6},
};

// The collection's entry `e` solved by Lemke with the collision solver's
// pivot limit, from its .guess when warm, with the sparse LU `lu` and
// `refactor_interval` pivots between refactorisations.
struct Solved {
  Lcp lcp;
  Result result;
  LemkeStats stats;
};
Solved solve_entry(const Path& e, SparseLu lu, int refactor_interval = LemkeOptions{}.refactor_interval) {
  Solved s{read_siconos_lcp(lcp_data(std::string(e.file) + ".dat")), {}, {}};
  std::vector<std::uint8_t> guess;
  LemkeOptions options;
  options.max_pivots = 15 * s.lcp.size() + 1000;  // the collision LCPs' limit (contact/impulse.hpp)
  options.sparse_lu = lu;
  options.refactor_interval = refactor_interval;
  if (e.warm) {
    guess = read_guess(lcp_data(std::string(e.file) + ".guess"));
    REQUIRE(static_cast<Index>(guess.size()) == s.lcp.size());
    options.start = &guess;
  }
  s.result = solve_lemke(s.lcp, options, &s.stats);
  return s;
}

TEST_CASE("lcp: Lemke walks the same pivot path as before its pivot was made cheaper") {
  for (const Path& e : kPaths) {
    const std::string file = e.file;
    CAPTURE(file);
    CAPTURE(e.warm);
    const Solved solved = solve_entry(e, SparseLu::umfpack, 100);
    const Lcp& lcp = solved.lcp;
    const Result& r = solved.result;
    const LemkeStats& stats = solved.stats;
    CHECK(to_string(r.status) == to_string(e.status));
    CHECK(r.pivots == e.pivots);
    CHECK(stats.solves == e.solves);
    if (e.status == Status::solved) {
      CHECK(r.residual <= 1e-12);
      check_complementary(lcp, r.z, 1e-9);
    }
  }
}

// KLU rounds otherwise than UMFPACK, so on the degenerate jams it may walk
// another path (to another valid answer): no pivot counts here, but every
// LCP of the collection above solved by the collision solver's settings,
// KLU for every sparse reduced basis, with the chain's acceptance (the one
// residual at FallbackOptions' 1e-9) and z, w = M z + q complementary,
// recomputed by lcp_checks.hpp. A warm start may end on a ray (lemke.hpp:
// the caller then starts from scratch), which the cold solve then covers.
TEST_CASE("lcp: Lemke with KLU solves the contact and jam LCPs of the collection") {
  const double tolerance = FallbackOptions{}.accept_residual;
  long klu_factorisations = 0;  // the small LCPs' bases go to the dense LU
  for (const Path& e : kPaths) {
    const std::string file = e.file;
    CAPTURE(file);
    CAPTURE(e.warm);
    const Solved solved = solve_entry(e, SparseLu::klu);
    const Lcp& lcp = solved.lcp;
    const Result& r = solved.result;
    const LemkeStats& stats = solved.stats;
    klu_factorisations += stats.sparse_refactorisations;
    MESSAGE(file << (e.warm ? " warm" : " cold") << ": " << to_string(r.status) << ", " << r.pivots
                 << " pivots (UMFPACK " << e.pivots << "), residual " << r.residual << ", KLU refactorisations "
                 << stats.sparse_refactorisations << " of " << stats.refactorisations);
    if (e.warm && r.status == Status::ray) continue;
    REQUIRE(r.status == Status::solved);
    CHECK(r.residual <= tolerance);
    check_complementary(lcp, r.z, tolerance);
  }
  CHECK(klu_factorisations > 0);
}

TEST_CASE("lcp: dense and sparse factorisations walk the same pivots on the friction LCPs") {
  for (const char* name : {"friction_m10_s1", "friction_m50_s2", "delassus_red_m50_s1"}) {
    CAPTURE(name);
    const Lcp lcp = read_siconos_lcp(lcp_data(std::string("contact/") + name + ".dat"));
    LemkeOptions dense, sparse;
    dense.factorization = Factorization::dense;
    sparse.factorization = Factorization::sparse;
    const Result a = solve_lemke(lcp, dense);
    const Result b = solve_lemke(lcp, sparse);
    REQUIRE(a.status == Status::solved);
    REQUIRE(b.status == Status::solved);
    CHECK(a.pivots == b.pivots);
    CHECK((a.z - b.z).cwiseAbs().maxCoeff() <= 1e-8 * (1.0 + a.z.cwiseAbs().maxCoeff()));
  }
}

TEST_SUITE_END();

}  // namespace
}  // namespace floesim::lcp
