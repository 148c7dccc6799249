// The publishing file driver (core/detail/h5_published.hpp): the file under
// its name is the file as of its last flush, byte for byte, until the next
// flush; nothing is written into it between two flushes.
#include <doctest/doctest.h>

#include <hdf5.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "core/detail/h5.hpp"
#include "core/detail/h5_published.hpp"

using namespace floesim;
namespace fs = std::filesystem;

TEST_SUITE_BEGIN("core");

namespace {
std::string bytes_of(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The datasets of a file opened afresh (as a reader after a kill would).
std::vector<double> read_back(const std::string& path, const std::string& name) {
  h5::Handle f = h5::open_file(path);
  return h5::read_doubles(h5::open_dataset(f, name, path), path + ": " + name);
}
}  // namespace

TEST_CASE("a published run file changes only at a flush, and only to a whole file") {
  const std::string path = (fs::temp_directory_path() / "floesim_published_test.h5").string();
  fs::remove(path);
  std::vector<double> a(5000, 1.5), b(7000, 2.5), c(3000, 3.5);
  {
    h5::Handle f = h5::create_file(path);
    REQUIRE(h5::is_published(f));
    // Nothing under the name before the first flush (an earlier file is removed).
    CHECK_FALSE(fs::exists(path));
    h5::write_doubles(f, "a", {a.size()}, a.data());
    REQUIRE(h5::flush(f));
    const std::string first = bytes_of(path);
    CHECK(read_back(path, "a") == a);
    CHECK(fs::exists(h5::working_path(path)));
    CHECK_FALSE(fs::exists(h5::previous_path(path)));

    // Writes without a flush (a record, or a checkpoint in the making, when
    // the process is killed): the published bytes do not move.
    h5::write_doubles(f, "b", {b.size()}, b.data());
    h5::remove(f, "a");
    CHECK(bytes_of(path) == first);
    CHECK(read_back(path, "a") == a);

    REQUIRE(h5::flush(f));
    CHECK(bytes_of(path) != first);
    CHECK(read_back(path, "b") == b);
    {
      h5::Handle r = h5::open_file(path);
      CHECK_FALSE(h5::exists(r, "a"));
    }
    // The working copy equals the published file after each flush, so the
    // next flush's ranges are all it lacks: a third flush is again whole.
    CHECK(bytes_of(h5::working_path(path)) == bytes_of(path));
    h5::write_doubles(f, "c", {c.size()}, c.data());
    REQUIRE(h5::flush(f));
    CHECK(read_back(path, "c") == c);
    CHECK(read_back(path, "b") == b);
  }
  // Closed: only the file is left.
  CHECK_FALSE(fs::exists(h5::working_path(path)));
  CHECK_FALSE(fs::exists(h5::previous_path(path)));
  CHECK(read_back(path, "c") == c);

  // Continued (a restart in place): published as it is until its first flush.
  const std::string before = bytes_of(path);
  {
    h5::Handle f = h5::open_file(path, true);
    REQUIRE(h5::is_published(f));
    h5::write_doubles(f, "d", {a.size()}, a.data());
    CHECK(bytes_of(path) == before);
    REQUIRE(h5::flush(f));
    CHECK(read_back(path, "d") == a);
    CHECK(read_back(path, "b") == b);
  }
  CHECK_FALSE(fs::exists(h5::working_path(path)));
  fs::remove(path);
}

TEST_CASE("a file written in place by choice has no helper copy, and removes stale ones") {
  const std::string path = (fs::temp_directory_path() / "floesim_in_place_test.h5").string();
  fs::remove(path);
  // Helper copies a killed published writer of `path` left: copies of an
  // older file, removed by the writer in place.
  for (const std::string& stale : {h5::working_path(path), h5::previous_path(path)}) std::ofstream(stale) << "old";
  std::vector<double> a(5000, 1.5), b(3000, 2.5);
  {
    h5::Handle f = h5::create_file(path, h5::Writing::in_place);
    REQUIRE(f.valid());
    CHECK_FALSE(h5::is_published(f));
    CHECK(fs::exists(path));  // written under its name from the start
    CHECK_FALSE(fs::exists(h5::working_path(path)));
    CHECK_FALSE(fs::exists(h5::previous_path(path)));
    h5::write_doubles(f, "a", {a.size()}, a.data());
    REQUIRE(h5::flush(f));
    CHECK_FALSE(fs::exists(h5::working_path(path)));
  }
  CHECK(read_back(path, "a") == a);
  {
    h5::Handle f = h5::open_file(path, true, h5::Writing::in_place);
    CHECK_FALSE(h5::is_published(f));
    h5::write_doubles(f, "b", {b.size()}, b.data());
    REQUIRE(h5::flush(f));
    CHECK_FALSE(fs::exists(h5::working_path(path)));
  }
  CHECK(read_back(path, "a") == a);
  CHECK(read_back(path, "b") == b);
  fs::remove(path);
}

TEST_CASE("a path that is not a regular file is written in place") {
  CHECK(h5::published_fapl("/dev/null") < 0);
}

TEST_SUITE_END();
