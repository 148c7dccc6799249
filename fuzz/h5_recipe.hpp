#pragma once
// Builds an HDF5 file from a small text "recipe", so that the pack fuzz
// targets reach floesim's reader logic (shapes, types, offsets, values,
// attributes) instead of spending their time in HDF5's own parser. One
// command per line, whitespace-separated; a line that does not parse is
// skipped, so every mutation still gives a file:
//
//   group PATH                           a group (intermediate groups made)
//   dset  PATH TYPE DIMS [V ...]         a contiguous dataset
//   cdset PATH TYPE DIMS [V ...]         a chunked dataset (extendible)
//   attr  OBJ NAME TYPE [V ...]          an attribute on a group or dataset
//   soft  PATH TARGET                    a soft link (may dangle)
//
// TYPE: f64 f32 i64 i32 u8 (numbers, "nan" and "inf" accepted), str (the rest
// of the line, fixed length), vstr (variable length). DIMS: comma-separated
// extents ("4,2"), or "-" for a scalar. Up to 65536 elements are written, the
// values repeated cyclically (zeros when none are given); above that the
// dataset only claims its extent and stores nothing, like a corrupted file.
//
// An input that starts with the HDF5 signature is not a recipe: it is written
// to the file as it is (byte-level fuzzing of real files), or skipped when
// FLOESIM_FUZZ_RECIPES_ONLY is set (CI: byte-level mutations also reach
// HDF5's own parser, whose known bugs would make a short run flaky; see
// docs/fuzzing.md).

#include <cstddef>
#include <cstdint>
#include <string>

namespace floesim::fuzz {

// Writes the file for `data` at `path`; returns false if HDF5 could not even
// create it (the caller then skips the input).
bool build_h5(const std::string& path, const std::uint8_t* data, std::size_t size);

}  // namespace floesim::fuzz
