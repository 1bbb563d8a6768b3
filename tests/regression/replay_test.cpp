// Replays the fuzz targets' inputs in the ordinary test builds (gcc, and ASan/UBSan in
// build-asan): the seed corpus in tests/fuzz/corpus/<target>/ and every input a fuzzer found
// wrong in tests/regression/inputs/<target>/, for MJCF also the malformed files' *.xml, its other
// seeds (docs/testing.md). The targets' own checks abort on a
// bug, which fails this test; each input must also come back from the target normally.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

// The four targets in one file, each under its own name.
#define LLVMFuzzerTestOneInput featherdrive_fuzz_urdf
#include "fuzz/fuzz_urdf.cpp"
#undef LLVMFuzzerTestOneInput
#define LLVMFuzzerTestOneInput featherdrive_fuzz_mjcf
#include "fuzz/fuzz_mjcf.cpp"
#undef LLVMFuzzerTestOneInput
#define LLVMFuzzerTestOneInput featherdrive_fuzz_scene
#include "fuzz/fuzz_scene.cpp"
#undef LLVMFuzzerTestOneInput
#define LLVMFuzzerTestOneInput featherdrive_fuzz_step
#include "fuzz/fuzz_step.cpp"
#undef LLVMFuzzerTestOneInput

namespace {

namespace fs = std::filesystem;
const fs::path kTests = FEATHERDRIVE_TESTS_DIR;

std::vector<fs::path> inputs(const std::string& target) {
  std::vector<fs::path> files;
  for (const fs::path& dir : {kTests / "fuzz" / "corpus" / target, kTests / "regression" / "inputs" / target})
    if (fs::is_directory(dir))
      for (const auto& entry : fs::directory_iterator(dir))
        if (entry.is_regular_file()) files.push_back(entry.path());
  if (target == "mjcf")  // the Makefile's FUZZ_SEEDS_mjcf
    for (const auto& entry : fs::directory_iterator(kTests / "data" / "malformed"))
      if (entry.is_regular_file() && entry.path().extension() == ".xml")
        files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

void replay(const std::string& target, int (*run)(const uint8_t*, size_t)) {
  const std::vector<fs::path> files = inputs(target);
  EXPECT_FALSE(files.empty()) << "no inputs for " << target;
  for (const fs::path& file : files) {
    SCOPED_TRACE(file.string());
    std::ifstream in(file, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NO_THROW(run(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()));
  }
}

TEST(FuzzReplay, Urdf) { replay("urdf", featherdrive_fuzz_urdf); }
TEST(FuzzReplay, Mjcf) { replay("mjcf", featherdrive_fuzz_mjcf); }
TEST(FuzzReplay, Scene) { replay("scene", featherdrive_fuzz_scene); }
TEST(FuzzReplay, Step) { replay("step", featherdrive_fuzz_step); }

}  // namespace
