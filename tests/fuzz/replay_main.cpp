// Stand-in for libFuzzer's main where clang/libFuzzer are missing: replays every file given
// (or every file in the folders given) through LLVMFuzzerTestOneInput, then -runs=N
// deterministic mutations of them (byte flips, insertions of OBJ tokens, truncations, splices).
// Flags other than -runs= are accepted and ignored, so ctest can pass libFuzzer's arguments.
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

void run(const std::string& input) {
    LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t*>(input.data()), input.size());
}

std::string readFile(const std::filesystem::path& path) {
    std::ifstream file(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
}

}  // namespace

int main(int argc, char** argv) {
    long runs = 0;
    std::vector<std::string> seeds;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg.rfind("-runs=", 0) == 0) {
            runs = std::strtol(arg.c_str() + 6, nullptr, 10);
        } else if (!arg.empty() && arg[0] == '-') {
            continue;  // a libFuzzer flag
        } else if (std::filesystem::is_directory(arg)) {
            for (const auto& entry : std::filesystem::directory_iterator(arg))
                if (entry.is_regular_file()) seeds.push_back(readFile(entry.path()));
        } else {
            seeds.push_back(readFile(arg));
        }
    }
    for (const std::string& seed : seeds) run(seed);
    if (seeds.empty()) seeds.emplace_back();
    static const char* const kTokens[] = {"v ", "vn ", "vt ", "f ", "o ", "g ", "/", "//", " ", "\n", "\r\n",
                                          "nan", "inf", "-", "+", ".", "e", "1e39", "1e-400", "0", "-1",
                                          "2147483647", "2147483648", "-2147483648", "99999999999", "#", "\t"};
    std::mt19937 rng(12345u);  // fixed: the same mutations every run
    for (long r = 0; r < runs; ++r) {
        std::string input = seeds[rng() % seeds.size()];
        const int edits = 1 + static_cast<int>(rng() % 4);
        for (int e = 0; e < edits; ++e) {
            const size_t at = input.empty() ? 0 : rng() % (input.size() + 1);
            switch (rng() % 4) {
                case 0:
                    if (!input.empty()) input[at % input.size()] = static_cast<char>(rng());
                    break;
                case 1: input.insert(at, kTokens[rng() % (sizeof kTokens / sizeof kTokens[0])]); break;
                case 2: input.resize(at); break;
                default: {
                    const std::string& other = seeds[rng() % seeds.size()];
                    const size_t from = other.empty() ? 0 : rng() % other.size();
                    input.insert(at, other.substr(from, rng() % 64));
                }
            }
        }
        run(input);
    }
    std::printf("obj_fuzz replay: %zu seeds, %ld mutations, no failure\n", seeds.size(), runs);
    return 0;
}
