#pragma once
// Reader and writer for LCPs in the Siconos Numerics text format (the test collection in
// data/lcp/, format described in its README.md):
//
//   n
//   storageType                     0 dense | 1 sparse-block (SBM) | 2 CSparse (refused)
//   size0 size1                     must both equal n
//   dense:  size0 size1, then size0*size1 numbers, M in COLUMN-MAJOR order
//           (value k is M(k % size0, k / size0): each text line is a column)
//   SBM:    nbblocks nb0 nb1
//           blocksize0[nb0] blocksize1[nb1]   cumulative end offsets of block rows/cols
//           filled1 filled2 index1[filled1] index2[filled2]   block-CSR pointers/columns
//           per stored block (in block-CSR order): its number, then rows*cols numbers
//           (column-major)
//   q: n numbers; anything after q is a comment.
//
// Every violation is refused with floesim::InputError "FILE:LINE: what was
// expected, what was found": a truncated file, a size mismatch, an inconsistent
// block structure, a token that is not a number, a non-finite number, or more
// numbers after q (a matrix larger than n declares). A dense M is returned
// dense; an SBM matrix sparse.

#include <string>
#include <string_view>

#include "contact/lcp/lcp.hpp"

namespace floesim::lcp {

Lcp read_siconos_lcp(const std::string& path);

// The same from text in memory; `name` stands for the file in messages.
Lcp parse_siconos_lcp(std::string_view text, const std::string& name);

// The LCP in that format: a dense M as storage 0, a sparse one as storage 1
// with 1 x 1 blocks (one block per stored entry, so the file is a CSR of M).
// Numbers are written in their shortest exact form, so reading the text back
// gives the same M and q bit for bit. `comment` (one or more lines, each
// written after "# ") follows q, where the reader ignores it.
std::string format_siconos_lcp(const Lcp& lcp, std::string_view comment = {});

// Writes format_siconos_lcp to `path`; throws floesim::RunError naming the
// file when it cannot be written.
void write_siconos_lcp(const Lcp& lcp, const std::string& path, std::string_view comment = {});

}  // namespace floesim::lcp
