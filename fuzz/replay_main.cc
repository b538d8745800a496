// The driver of the reader fuzzers in every build that is not a libFuzzer
// build (docs/fuzzing.md, "In CI"): each fuzzer's LLVMFuzzerTestOneInput is
// linked with this main, which
//   1. runs every file of the given corpus folders once (the committed seeds
//      and every crash reproducer that became a seed), then
//   2. runs `--mutations N` inputs made from those files by random byte
//      edits (flip, insert, delete, duplicate a span, splice two files,
//      insert a dictionary token), seeded by `--seed`, so that a CI run is
//      repeatable.
// It is a blind fuzzer, not a coverage-guided one: the coverage-guided runs
// are fuzz/run.sh's (clang, libFuzzer). In the sanitized CI build every
// input runs under ASan and UBSan; a finding aborts the process with the
// input's recipe (seed and mutation number) on stderr.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

namespace {

using Bytes = std::vector<uint8_t>;

Bytes ReadAll(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// libFuzzer dictionary lines: name="token" or "token" (escapes \" \\ \xNN).
std::vector<Bytes> ReadDictionary(const std::filesystem::path& p) {
  std::vector<Bytes> out;
  std::ifstream in(p);
  std::string line;
  while (std::getline(in, line)) {
    const size_t a = line.find('"'), b = line.rfind('"');
    if (line.empty() || line[0] == '#' || a == std::string::npos || b <= a) continue;
    Bytes token;
    for (size_t i = a + 1; i < b; ++i) {
      if (line[i] == '\\' && i + 1 < b) {
        if (line[i + 1] == 'x' && i + 3 < b) {
          token.push_back(static_cast<uint8_t>(std::stoi(line.substr(i + 2, 2), nullptr, 16)));
          i += 3;
        } else {
          token.push_back(static_cast<uint8_t>(line[++i]));
        }
      } else {
        token.push_back(static_cast<uint8_t>(line[i]));
      }
    }
    out.push_back(token);
  }
  return out;
}

Bytes Mutate(const std::vector<Bytes>& corpus, const std::vector<Bytes>& dict,
             std::mt19937_64* rng) {
  auto pick = [&](size_t n) { return std::uniform_int_distribution<size_t>(0, n - 1)(*rng); };
  Bytes x = corpus[pick(corpus.size())];
  const int edits = 1 + static_cast<int>(pick(4));
  for (int e = 0; e < edits; ++e) {
    const size_t at = x.empty() ? 0 : pick(x.size() + 1);
    switch (pick(6)) {
      case 0:  // flip a bit
        if (!x.empty()) x[std::min(at, x.size() - 1)] ^= static_cast<uint8_t>(1u << pick(8));
        break;
      case 1:  // insert a random byte
        x.insert(x.begin() + at, static_cast<uint8_t>(pick(256)));
        break;
      case 2:  // delete a span
        if (!x.empty()) {
          const size_t from = std::min(at, x.size() - 1);
          x.erase(x.begin() + from, x.begin() + std::min(x.size(), from + 1 + pick(16)));
        }
        break;
      case 3: {  // duplicate a span
        if (x.empty()) break;
        const size_t from = pick(x.size());
        const Bytes span(x.begin() + from, x.begin() + std::min(x.size(), from + 1 + pick(64)));
        x.insert(x.begin() + std::min(at, x.size()), span.begin(), span.end());
        break;
      }
      case 4: {  // splice: a tail of another corpus file
        const Bytes& other = corpus[pick(corpus.size())];
        if (other.empty()) break;
        const size_t from = pick(other.size());
        x.resize(std::min(at, x.size()));
        x.insert(x.end(), other.begin() + from, other.end());
        break;
      }
      default:  // a dictionary token
        if (!dict.empty()) {
          const Bytes& t = dict[pick(dict.size())];
          x.insert(x.begin() + std::min(at, x.size()), t.begin(), t.end());
        }
    }
  }
  return x;
}

int Usage(const char* argv0) {
  std::fprintf(stderr,
               "usage: %s [--mutations N] [--seed S] [--dict FILE] [--save-mutation K FILE]\n"
               "          CORPUS_DIR_OR_FILE...\n"
               "--save-mutation K FILE writes mutation K to FILE without running anything\n",
               argv0);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  long mutations = 0;
  unsigned long long seed = 1;
  std::vector<Bytes> dict;
  std::vector<std::filesystem::path> inputs;
  long save = -1;
  std::string save_path;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--save-mutation" && i + 2 < argc) {
      save = std::strtol(argv[++i], nullptr, 10);
      save_path = argv[++i];
      continue;
    }
    if ((a == "--mutations" || a == "--seed" || a == "--dict") && i + 1 < argc) {
      const std::string v = argv[++i];
      if (a == "--mutations") mutations = std::strtol(v.c_str(), nullptr, 10);
      if (a == "--seed") seed = std::strtoull(v.c_str(), nullptr, 10);
      if (a == "--dict") dict = ReadDictionary(v);
    } else if (!a.empty() && a[0] == '-') {
      return Usage(argv[0]);
    } else {
      inputs.emplace_back(a);
    }
  }
  std::vector<std::filesystem::path> files;
  for (const auto& p : inputs) {
    if (std::filesystem::is_directory(p)) {
      for (const auto& e : std::filesystem::recursive_directory_iterator(p)) {
        if (e.is_regular_file()) files.push_back(e.path());
      }
    } else if (std::filesystem::is_regular_file(p)) {
      files.push_back(p);
    } else {
      std::fprintf(stderr, "%s: no such file or folder\n", p.string().c_str());
      return 2;
    }
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) return Usage(argv[0]);
  std::vector<Bytes> corpus;
  for (const auto& f : files) {
    corpus.push_back(ReadAll(f));
    if (save >= 0) continue;
    std::fprintf(stderr, "replay %s\n", f.string().c_str());
    LLVMFuzzerTestOneInput(corpus.back().data(), corpus.back().size());
  }
  std::mt19937_64 rng(seed);
  if (save >= 0) mutations = save + 1;
  for (long k = 0; k < mutations; ++k) {
    const Bytes x = Mutate(corpus, dict, &rng);
    if (k == save) {
      std::ofstream(save_path, std::ios::binary)
          .write(reinterpret_cast<const char*>(x.data()), static_cast<std::streamsize>(x.size()));
      return 0;
    }
    if (save >= 0) continue;
    // The recipe of the input in case it aborts: rerun with --mutations k+1.
    std::fprintf(stderr, "\rmutation %ld (seed %llu)", k, seed);
    LLVMFuzzerTestOneInput(x.data(), x.size());
  }
  std::fprintf(stderr, "\n%zu corpus files and %ld mutations: no finding\n", corpus.size(),
               mutations);
  return 0;
}
