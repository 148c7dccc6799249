// The Siconos-format reader: layouts read right, every kind of malformed input
// refused with a message naming the file, the line and what was wrong.
#include <doctest/doctest.h>

#include <string>

#include "contact/lcp/siconos_io.hpp"
#include "core/error.hpp"

namespace floesim::lcp {
namespace {

TEST_SUITE_BEGIN("contact");

// The InputError message for `text`, or "" when it parsed.
std::string refusal(const std::string& text) {
  try {
    parse_siconos_lcp(text, "bad.dat");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

const std::string kHeader2 = "2\n0\n2\n2\n2 2\n";

TEST_CASE("lcp io: a dense file is column-major - the comment after q ignored") {
  const Lcp lcp = parse_siconos_lcp(kHeader2 + "1 2\n3 4\n-1 -2\n# a comment 5 6\n", "ok.dat");
  const auto& M = std::get<DenseMatrix>(lcp.M);
  CHECK(M(0, 0) == 1.0);
  CHECK(M(1, 0) == 2.0);  // the first line is the first column
  CHECK(M(0, 1) == 3.0);
  CHECK(lcp.q(1) == -2.0);
}

TEST_CASE("lcp io: a sparse-block file becomes a sparse M") {
  // 3 x 3 in blocks {0,1} x {2}: one 2x2 diagonal block and one 1x1 block.
  const std::string text =
      "3\n1\n3\n3\n2\n2 2\n2 3\n2 3\n3 2\n0 1 2\n0 1\n"
      "0\n1 0 5 2\n1\n7\n-1 -1 -1\n";
  const Lcp lcp = parse_siconos_lcp(text, "ok.dat");
  REQUIRE(lcp.is_sparse());
  const DenseMatrix M(std::get<SparseMatrix>(lcp.M));
  CHECK(M(0, 0) == 1.0);
  CHECK(M(0, 1) == 5.0);
  CHECK(M(1, 1) == 2.0);
  CHECK(M(2, 2) == 7.0);
  CHECK(M(2, 0) == 0.0);
}

TEST_CASE("lcp io: malformed files are refused naming the file and line and the reason") {
  struct Case {
    const char* what;
    std::string text;
    const char* expect;
  };
  const Case cases[] = {
      {"empty", "", "end of file"},
      {"n not an integer", "two\n", "n (the LCP size)"},
      {"n zero", "0\n0\n", "out of range"},
      {"unknown storage", "2\n5\n", "storageType"},
      {"CSparse storage", "2\n2\n2 2\n", "not supported"},
      {"size mismatch", "2\n0\n3\n3\n3 3\n", "does not match n"},
      {"dense size mismatch", "2\n0\n2\n2\n2 3\n", "do not match n"},
      {"truncated matrix", kHeader2 + "1 2\n3\n", "end of file"},
      {"truncated q", kHeader2 + "1 2\n3 4\n-1\n", "end of file"},
      {"not a number", kHeader2 + "1 x\n3 4\n-1 -1\n", "found 'x'"},
      {"nan entry", kHeader2 + "1 2\nnan 4\n-1 -1\n", "not finite"},
      {"inf in q", kHeader2 + "1 2\n3 4\n-1 inf\n", "not finite"},
      {"matrix larger than declared", kHeader2 + "1 2 3\n4 5 6\n7 8 9\n-1 -1 -1\n",
       "more numbers after q"},
      {"block offsets not reaching n", "3\n1\n3\n3\n1\n1 1\n2\n3\n2 1\n0 1\n0\n0\n1 2 3 4\n",
       "blocksize0 ends at 2"},
      {"block column out of range", "2\n1\n2\n2\n1\n1 1\n2\n2\n2 1\n0 1\n3\n", "index2[0]"},
      {"wrong block number", "2\n1\n2\n2\n1\n1 1\n2\n2\n2 1\n0 1\n0\n4\n", "block number"},
      {"truncated block", "2\n1\n2\n2\n1\n1 1\n2\n2\n2 1\n0 1\n0\n0\n1 2\n", "entries of block 0"},
  };
  for (const Case& c : cases) {
    const std::string name = c.what;
    CAPTURE(name);
    const std::string message = refusal(c.text);
    CAPTURE(message);
    CHECK(contains(message, "bad.dat"));
    CHECK(contains(message, c.expect));
  }
  CHECK(contains(refusal(kHeader2 + "1 2\n3 x\n-1 -1\n"), "bad.dat:7:"));
}

// The writer's text read back by the reader: the same LCP bit for bit
// (numbers in shortest exact form), dense and sparse, the comment ignored.
TEST_CASE("lcp io: written LCPs read back exactly") {
  DenseMatrix D(3, 3);
  D << 1.0, 0.1, 0.0,
       0.1, 2.0 / 3.0, -1e-300,
       0.7, -1.0, 0.0;
  Lcp dense;
  dense.M = D;
  dense.q = Vector::Zero(3);
  dense.q << -1.0 / 3.0, 2.5e-17, 4.0;
  const Lcp back = parse_siconos_lcp(format_siconos_lcp(dense, "a failed LCP\nsecond line 5 6"), "w.dat");
  REQUIRE(!back.is_sparse());
  CHECK((std::get<DenseMatrix>(back.M).array() == D.array()).all());
  CHECK((back.q.array() == dense.q.array()).all());

  Lcp sparse;
  SparseMatrix S(5, 5);  // row and column 4 empty
  S.insert(0, 0) = 1.0;
  S.insert(2, 0) = 1.0 / 7.0;
  S.insert(1, 3) = -0.7;
  S.insert(3, 3) = 3e-12;
  sparse.M = S;
  sparse.q = Vector::Constant(5, -0.1);
  const Lcp sback = parse_siconos_lcp(format_siconos_lcp(sparse, "comment"), "s.dat");
  REQUIRE(sback.is_sparse());
  CHECK(Eigen::MatrixXd(std::get<SparseMatrix>(sback.M)) == Eigen::MatrixXd(S));
  CHECK((sback.q.array() == sparse.q.array()).all());
}

TEST_CASE("lcp io: an LCP written to a folder that does not exist is a run error naming it") {
  Lcp lcp;
  lcp.M = DenseMatrix::Identity(1, 1);
  lcp.q = Vector::Constant(1, -1.0);
  CHECK_THROWS_WITH_AS(write_siconos_lcp(lcp, "/nonexistent/dir/p.dat"),
                       doctest::Contains("/nonexistent/dir/p.dat"), RunError);
}

TEST_CASE("lcp io: a missing file is an input error naming it") {
  CHECK_THROWS_WITH_AS(read_siconos_lcp("/nonexistent/dir/p.dat"),
                       doctest::Contains("/nonexistent/dir/p.dat"), InputError);
}

TEST_SUITE_END();

}  // namespace
}  // namespace floesim::lcp
