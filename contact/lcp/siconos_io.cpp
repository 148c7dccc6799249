#include "contact/lcp/siconos_io.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <vector>

#include "core/error.hpp"

namespace floesim::lcp {

namespace {

// Larger LCPs are certainly not what a text file should hold; the bound keeps a
// corrupt header from asking for an absurd allocation.
constexpr long kMaxSize = 1'000'000;

struct Token {
  std::string_view text;
  long line;
};

class TokenReader {
public:
  TokenReader(std::string_view text, std::string name) : name_(std::move(name)) {
    long line = 1;
    std::size_t i = 0;
    while (i < text.size()) {
      const char c = text[i];
      if (c == '\n') ++line;
      if (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v') {
        ++i;
        continue;
      }
      const std::size_t start = i;
      while (i < text.size() && !std::isspace(static_cast<unsigned char>(text[i]))) ++i;
      tokens_.push_back({text.substr(start, i - start), line});
    }
  }

  [[noreturn]] void fail(long line, const std::string& message) const {
    throw InputError(where(name_, line, "", message));
  }
  long line() const { return at_ < tokens_.size() ? tokens_[at_].line : last_line(); }
  long last_line() const { return tokens_.empty() ? 1 : tokens_.back().line; }
  std::size_t remaining() const { return tokens_.size() - at_; }

  // Fails, naming `what`, unless at least `count` more tokens exist.
  void require(std::size_t count, const std::string& what) const {
    if (remaining() < count)
      fail(last_line(), "unexpected end of file: expected " + what + " (" +
                            std::to_string(count) + " numbers, " + std::to_string(remaining()) +
                            " left; file truncated or sizes inconsistent)");
  }

  long integer(const std::string& what, long lo, long hi) {
    require(1, what);
    const Token& t = tokens_[at_++];
    long value = 0;
    const auto [end, ec] = std::from_chars(t.text.data(), t.text.data() + t.text.size(), value);
    if (ec != std::errc() || end != t.text.data() + t.text.size())
      fail(t.line, "expected " + what + " (an integer), found '" + std::string(t.text) + "'");
    if (value < lo || value > hi)
      fail(t.line, what + " = " + std::to_string(value) + " is out of range [" +
                       std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return value;
  }

  double number(const std::string& what) {
    require(1, what);
    const Token& t = tokens_[at_++];
    double value = 0.0;
    if (!parse_double(t.text, value))
      fail(t.line, "expected " + what + " (a number), found '" + std::string(t.text) + "'");
    if (!std::isfinite(value))
      fail(t.line, what + " is not finite ('" + std::string(t.text) + "')");
    return value;
  }

  // Anything after q is a comment, unless it starts with a number: then the
  // file holds more numbers than its sizes declare.
  void expect_only_comment() const {
    if (remaining() == 0) return;
    const Token& t = tokens_[at_];
    double ignored = 0.0;
    if (parse_double(t.text, ignored))
      fail(t.line, "more numbers after q ('" + std::string(t.text) +
                       "'): the matrix holds more entries than its declared size");
  }

private:
  static bool parse_double(std::string_view s, double& value) {
    if (!s.empty() && s.front() == '+') s.remove_prefix(1);
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
    return (ec == std::errc() || ec == std::errc::result_out_of_range) &&
           end == s.data() + s.size() && !s.empty();
  }

  std::string name_;
  std::vector<Token> tokens_;
  std::size_t at_ = 0;
};

std::string entry_name(const char* matrix, Index i, Index j) {
  return std::string(matrix) + "(" + std::to_string(i) + ", " + std::to_string(j) + ")";
}

DenseMatrix read_dense(TokenReader& in, Index n) {
  const long line = in.line();
  const long rows = in.integer("dense size0", 0, kMaxSize);
  const long cols = in.integer("dense size1", 0, kMaxSize);
  if (rows != n || cols != n)
    in.fail(line, "dense sizes " + std::to_string(rows) + " x " + std::to_string(cols) +
                      " do not match n = " + std::to_string(n));
  in.require(static_cast<std::size_t>(n * n + n), "the n*n entries of M and the n of q");
  DenseMatrix M(n, n);
  for (Index j = 0; j < n; ++j)  // column-major: one column after the other
    for (Index i = 0; i < n; ++i) M(i, j) = in.number(entry_name("M", i, j));
  return M;
}

// Reads `count` cumulative end offsets, strictly increasing, the last == total.
std::vector<Index> read_offsets(TokenReader& in, long count, Index total, const char* what) {
  std::vector<Index> ends;
  Index previous = 0;
  for (long b = 0; b < count; ++b) {
    const long line = in.line();
    const Index end = in.integer(std::string(what) + "[" + std::to_string(b) + "]", 1, total);
    if (end <= previous) in.fail(line, std::string(what) + " must increase strictly");
    ends.push_back(end);
    previous = end;
  }
  if (previous != total)
    in.fail(in.line(), std::string(what) + " ends at " + std::to_string(previous) +
                           ", not at the matrix size " + std::to_string(total));
  return ends;
}

SparseMatrix read_sparse_block(TokenReader& in, Index n) {
  const long nbblocks = in.integer("nbblocks", 0, kMaxSize);
  const long nb0 = in.integer("nb0 (block rows)", 1, n);
  const long nb1 = in.integer("nb1 (block columns)", 1, n);
  if (nbblocks > nb0 * nb1)
    in.fail(in.line(), "nbblocks = " + std::to_string(nbblocks) + " exceeds nb0 * nb1");
  const std::vector<Index> row_ends = read_offsets(in, nb0, n, "blocksize0");
  const std::vector<Index> col_ends = read_offsets(in, nb1, n, "blocksize1");
  const long filled1 = in.integer("filled1", nb0 + 1, nb0 + 1);
  const long filled2 = in.integer("filled2", nbblocks, nbblocks);
  std::vector<long> index1(static_cast<std::size_t>(filled1));
  for (long b = 0; b < filled1; ++b) {
    const long line = in.line();
    index1[b] = in.integer("index1[" + std::to_string(b) + "]", 0, nbblocks);
    if ((b == 0 && index1[b] != 0) || (b > 0 && index1[b] < index1[b - 1]))
      in.fail(line, "index1 must start at 0 and not decrease");
  }
  if (index1.back() != nbblocks)
    in.fail(in.line(), "index1 ends at " + std::to_string(index1.back()) +
                           ", not at nbblocks = " + std::to_string(nbblocks));
  std::vector<long> index2(static_cast<std::size_t>(filled2));
  for (long b = 0; b < filled2; ++b)
    index2[b] = in.integer("index2[" + std::to_string(b) + "]", 0, nb1 - 1);

  std::vector<Eigen::Triplet<double, int>> entries;
  for (long br = 0; br < nb0; ++br) {
    const Index r0 = br == 0 ? 0 : row_ends[br - 1];
    const Index rows = row_ends[br] - r0;
    for (long k = index1[br]; k < index1[br + 1]; ++k) {
      const long bc = index2[k];
      if (k > index1[br] && bc <= index2[k - 1])
        in.fail(in.line(), "index2 must increase within block row " + std::to_string(br));
      const Index c0 = bc == 0 ? 0 : col_ends[bc - 1];
      const Index cols = col_ends[bc] - c0;
      const long line = in.line();
      const long number = in.integer("block number", 0, nbblocks - 1);
      if (number != k)
        in.fail(line, "block number " + std::to_string(number) + " found where block " +
                          std::to_string(k) + " was expected");
      in.require(static_cast<std::size_t>(rows * cols),
                 "the " + std::to_string(rows * cols) + " entries of block " + std::to_string(k));
      for (Index j = 0; j < cols; ++j)
        for (Index i = 0; i < rows; ++i) {
          const double v = in.number(entry_name("M", r0 + i, c0 + j));
          if (v != 0.0)
            entries.emplace_back(static_cast<int>(r0 + i), static_cast<int>(c0 + j), v);
        }
    }
  }
  SparseMatrix M(n, n);
  M.setFromTriplets(entries.begin(), entries.end());
  M.makeCompressed();
  return M;
}

}  // namespace

Lcp parse_siconos_lcp(std::string_view text, const std::string& name) {
  TokenReader in(text, name);
  const Index n = in.integer("n (the LCP size)", 1, kMaxSize);
  const long storage_line = in.line();
  const long storage = in.integer("storageType", 0, 2);
  if (storage == 2)
    in.fail(storage_line, "storageType 2 (CSparse) is not supported; expected 0 or 1");
  const long line = in.line();
  const long size0 = in.integer("size0", 0, kMaxSize);
  const long size1 = in.integer("size1", 0, kMaxSize);
  if (size0 != n || size1 != n)
    in.fail(line, "matrix size " + std::to_string(size0) + " x " + std::to_string(size1) +
                      " does not match n = " + std::to_string(n));
  Lcp lcp;
  if (storage == 0)
    lcp.M = read_dense(in, n);
  else
    lcp.M = read_sparse_block(in, n);
  in.require(static_cast<std::size_t>(n), "the " + std::to_string(n) + " entries of q");
  lcp.q.resize(n);
  for (Index i = 0; i < n; ++i) lcp.q(i) = in.number("q[" + std::to_string(i) + "]");
  in.expect_only_comment();
  return lcp;
}

Lcp read_siconos_lcp(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError(where(path, 0, "", "cannot open the LCP file"));
  std::ostringstream text;
  text << file.rdbuf();
  if (file.bad()) throw InputError(where(path, 0, "", "read error"));
  return parse_siconos_lcp(text.str(), path);
}

namespace {
void put(std::string& out, double v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}
}  // namespace

std::string format_siconos_lcp(const Lcp& lcp, std::string_view comment) {
  const Index n = lcp.size();
  std::string out = std::to_string(n) + "\n";
  if (const auto* D = std::get_if<DenseMatrix>(&lcp.M)) {
    out += "0\n" + std::to_string(n) + "\n" + std::to_string(n) + "\n";
    out += std::to_string(n) + " " + std::to_string(n) + "\n";
    for (Index j = 0; j < n; ++j) {  // column-major: a line per column
      for (Index i = 0; i < n; ++i) {
        if (i) out += ' ';
        put(out, (*D)(i, j));
      }
      out += '\n';
    }
  } else {
    // Block-CSR of 1 x 1 blocks: rows of M in order, columns increasing within a row.
    const Eigen::SparseMatrix<double, Eigen::RowMajor, int> R(std::get<SparseMatrix>(lcp.M));
    std::vector<std::pair<Index, double>> entries;  // (column, value), row by row
    std::vector<Index> row_start{0};
    for (Index i = 0; i < n; ++i) {
      for (Eigen::SparseMatrix<double, Eigen::RowMajor, int>::InnerIterator it(R, i); it; ++it)
        if (it.value() != 0.0) entries.emplace_back(it.index(), it.value());
      row_start.push_back(static_cast<Index>(entries.size()));
    }
    const std::string nb = std::to_string(entries.size());
    out += "1\n" + std::to_string(n) + "\n" + std::to_string(n) + "\n";
    out += nb + " " + std::to_string(n) + " " + std::to_string(n) + "\n";
    for (int twice = 0; twice < 2; ++twice) {  // blocksize0 then blocksize1: 1, 2, ..., n
      for (Index i = 1; i <= n; ++i) out += std::to_string(i) + (i == n ? "\n" : " ");
    }
    out += std::to_string(n + 1) + " " + nb + "\n";
    for (Index i = 0; i <= n; ++i) out += std::to_string(row_start[static_cast<std::size_t>(i)]) + (i == n ? "\n" : " ");
    for (std::size_t k = 0; k < entries.size(); ++k) out += std::to_string(entries[k].first) + " ";
    out += "\n";
    for (std::size_t k = 0; k < entries.size(); ++k) {
      out += std::to_string(k) + " ";
      put(out, entries[k].second);
      out += '\n';
    }
  }
  for (Index i = 0; i < n; ++i) {
    if (i) out += ' ';
    put(out, lcp.q(i));
  }
  out += '\n';
  std::size_t at = 0;
  while (at < comment.size()) {
    const std::size_t end = std::min(comment.find('\n', at), comment.size());
    out += "# ";
    out.append(comment.substr(at, end - at));
    out += '\n';
    at = end + 1;
  }
  return out;
}

void write_siconos_lcp(const Lcp& lcp, const std::string& path, std::string_view comment) {
  const std::string text = format_siconos_lcp(lcp, comment);
  std::ofstream file(path, std::ios::binary);
  if (file) file.write(text.data(), static_cast<std::streamsize>(text.size()));
  if (file) file.close();
  if (!file) throw RunError(path + ": cannot write the LCP file");
}

}  // namespace floesim::lcp
