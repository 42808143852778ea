// light_lut_error — how wrong the light-sample LUT is, and how much of it the certified mode leaves
// uncertain, against the exact test, over random planes through random points near the light.
//
//   light_lut_error [--resolutions 32,64,128,256] [--samples 128,512,1024] [--planes 1000000]
//                   [--shape sphere|disk|rectangle|ellipsoid] [--pattern stratified|low-discrepancy]
//                   [--mapping octahedral|spherical] [--asymmetric]
//                   [--seed S] [--json out.json]
//
// For each (resolution, N) it builds the certified LUT (or, when the table would exceed --max-table
// bytes, evaluates the same texels on demand with lightLutTexel, which tests/light_lut_test.cpp
// proves equal to the generated table) and looks every plane up in every table of the set:
//   wrong      bits where the seed mode (centre sampling) differs from the exact test;
//   uncertain  bits the certified mode leaves to an exact test;
//   wrong_certain  certain bits that differ from the exact test (must be 0);
//   conservative   bits where "behind for some plane of the cell" (centre | uncertain) differs;
// as fractions of all sample bits, and of the bits of planes that cut the bounding sphere.
// Planes: normal uniform on the sphere, through a point uniform in [-1.5, 1.5]^3 (light units).
#include <penumbra/light_lut.hpp>
#include <penumbra/light_samples.hpp>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <bitset>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <random>

namespace {

using glm::dvec3;
using glm::dvec4;

int popcount(const penumbra::LutMask& m) {
    int c = 0;
    for (uint32_t w : m) c += static_cast<int>(std::bitset<32>(w).count());
    return c;
}

struct Row {
    uint32_t resolution = 0, samples = 0;
    uint64_t bits = 0, cut_bits = 0, wrong = 0, uncertain = 0, wrong_certain = 0, conservative = 0;
    uint64_t table_bytes = 0;
    bool on_demand = false;
    double generate_seconds = 0, measure_seconds = 0;
};

std::vector<uint32_t> parseList(const std::string& text) {
    std::vector<uint32_t> out;
    size_t start = 0;
    while (start <= text.size()) {
        const size_t comma = text.find(',', start);
        out.push_back(static_cast<uint32_t>(std::stoul(text.substr(start, comma - start))));
        if (comma == std::string::npos) break;
        start = comma + 1;
    }
    return out;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"light_lut_error: wrong and uncertain bits of the light-sample LUT vs the exact test"};
    std::string resolutions = "32,64,128,256", sample_counts = "128,512,1024", shape = "sphere", mapping = "octahedral";
    std::string pattern = "stratified";
    std::string json_path;
    uint64_t planes = 1000000, max_table = 1ull << 30;
    uint32_t seed = 1;
    bool asymmetric = false;
    app.add_option("--resolutions", resolutions, "comma-separated R (R^3 texels per table)");
    app.add_option("--samples", sample_counts, "comma-separated N (multiples of 32, <= 1024)");
    app.add_option("--planes", planes, "random planes per configuration");
    app.add_option("--shape", shape, "light shape (light_samples.hpp; ellipsoid 1 x 0.5 x 0.25, rectangle 1 x 0.5)")
        ->check(CLI::IsMember({"sphere", "disk", "rectangle", "ellipsoid"}));
    app.add_option("--pattern", pattern, "light-sample pattern")->check(CLI::IsMember({"stratified", "low-discrepancy"}));
    app.add_option("--mapping", mapping, "normal mapping")->check(CLI::IsMember({"octahedral", "spherical"}));
    app.add_flag("--asymmetric", asymmetric, "store d in [-1, 1] instead of using the (n, d) <-> (-n, -d) symmetry");
    app.add_option("--seed", seed, "plane and sample seed");
    app.add_option("--max-table", max_table, "largest table built in memory (bytes); larger ones are evaluated on demand");
    app.add_option("--json", json_path, "write the rows as JSON");
    CLI11_PARSE(app, argc, argv);

    std::vector<Row> rows;
    try {
        for (const uint32_t n : parseList(sample_counts)) {
            // One set of N samples of the light, in its normalised space (what the LUT indexes).
            penumbra::Light light;
            light.shape = shape == "sphere"      ? penumbra::LightShape::Sphere
                          : shape == "disk"      ? penumbra::LightShape::Disk
                          : shape == "rectangle" ? penumbra::LightShape::Rectangle
                                                 : penumbra::LightShape::Ellipsoid;
            light.size = shape == "ellipsoid" ? dvec3(1.0, 0.5, 0.25) : shape == "rectangle" ? dvec3(1.0, 0.5, 0.0) : dvec3(1.0);
            penumbra::LightSampleOptions sample_options;
            sample_options.count = n;
            sample_options.sets = 1;
            sample_options.seed = seed;
            sample_options.pattern =
                pattern == "stratified" ? penumbra::SamplePattern::Stratified : penumbra::SamplePattern::LowDiscrepancy;
            const std::vector<dvec3> samples = penumbra::makeLightSampleSets(light, sample_options).local;
            for (const uint32_t r : parseList(resolutions)) {
                penumbra::LightLutOptions options;
                options.resolution = r;
                options.certified = true;
                options.symmetric = !asymmetric;
                options.mapping = mapping == "octahedral" ? penumbra::LutNormalMapping::Octahedral
                                                          : penumbra::LutNormalMapping::Spherical;
                const penumbra::LightLutSetup setup = penumbra::lightLutSetup(samples, n, options);
                Row row;
                row.resolution = r;
                row.samples = n;
                row.table_bytes = setup.tableBytes();
                row.on_demand = setup.tableBytes() > max_table;
                std::vector<uint32_t> lut;
                auto t0 = std::chrono::steady_clock::now();
                if (!row.on_demand) {
                    lut = penumbra::generateLightLut(setup, [&](double f) {
                        std::fprintf(stderr, "\r  generating R=%u N=%u: %3.0f%%", r, n, 100.0 * f);
                        return true;
                    });
                    std::fprintf(stderr, "\n");
                }
                auto t1 = std::chrono::steady_clock::now();
                row.generate_seconds = std::chrono::duration<double>(t1 - t0).count();
                std::mt19937_64 rng(seed * 1000003ull + r * 7919ull + n);
                std::normal_distribution<double> normal;
                std::uniform_real_distribution<double> uniform(-1.5, 1.5);
                for (uint64_t k = 0; k < planes; ++k) {
                    if (k % 100000 == 0)
                        std::fprintf(stderr, "\r  measuring R=%u N=%u: %3.0f%%", r, n, 100.0 * double(k) / double(planes));
                    dvec3 normal_dir;
                    do normal_dir = dvec3(normal(rng), normal(rng), normal(rng));
                    while (glm::dot(normal_dir, normal_dir) < 1e-12);
                    normal_dir = glm::normalize(normal_dir);
                    const dvec3 point(uniform(rng), uniform(rng), uniform(rng));
                    const dvec4 plane(normal_dir, -glm::dot(normal_dir, point));
                    const penumbra::LutCell cell = penumbra::lightLutLocate(setup.params, plane);
                    for (uint32_t table = 0; table < setup.params.tables; ++table) {
                        const penumbra::LutMask valid = penumbra::lightLutValidMask(setup.params, table);
                        const int valid_bits = popcount(valid);
                        row.bits += static_cast<uint64_t>(valid_bits);
                        if (cell.trivial != 0) continue;  // answered exactly without the table
                        row.cut_bits += static_cast<uint64_t>(valid_bits);
                        penumbra::LutAnswer answer;
                        if (row.on_demand) {
                            answer = penumbra::lightLutTexel(setup, table, cell.texel);
                            if (cell.flip)
                                for (int w = 0; w < 4; ++w) answer.centre[w] = ~answer.centre[w] & valid[w];
                        } else {
                            answer = penumbra::lightLutLookup(setup.params, lut.data(), table, plane);
                        }
                        const penumbra::LutMask exact = penumbra::exactBehind(setup, table, plane);
                        for (int w = 0; w < 4; ++w) {
                            const uint32_t differs = answer.centre[w] ^ exact[w];
                            row.wrong += std::bitset<32>(differs).count();
                            row.uncertain += std::bitset<32>(answer.uncertain[w]).count();
                            row.wrong_certain += std::bitset<32>(differs & ~answer.uncertain[w]).count();
                            row.conservative += std::bitset<32>((answer.centre[w] | answer.uncertain[w]) ^ exact[w]).count();
                        }
                    }
                }
                row.measure_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
                std::fprintf(stderr, "\r  measured R=%u N=%u in %.1f s          \n", r, n, row.measure_seconds);
                rows.push_back(row);
            }
        }
    } catch (const penumbra::Error& e) {
        std::cerr << "light_lut_error: " << e.what() << "\n";
        return 1;
    }

    std::printf("shape %s (%s), mapping %s, %s, %llu planes per row\n", shape.c_str(), pattern.c_str(), mapping.c_str(),
                asymmetric ? "d in [-1, 1]" : "symmetric (d in [0, 1])", static_cast<unsigned long long>(planes));
    std::printf("| R | N | table MiB | cut | wrong (seed) | uncertain (certified) | wrong certain | conservative wrong | wrong / cut | uncertain / cut |\n");
    std::printf("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n");
    nlohmann::ordered_json out = nlohmann::ordered_json::array();
    for (const Row& row : rows) {
        const double bits = double(row.bits), cut = double(std::max<uint64_t>(row.cut_bits, 1));
        std::printf("| %u | %u | %.1f%s | %.3f | %.3e | %.3e | %llu | %.3e | %.3e | %.3e |\n", row.resolution, row.samples,
                    double(row.table_bytes) / 1048576.0, row.on_demand ? " (on demand)" : "", double(row.cut_bits) / bits,
                    double(row.wrong) / bits, double(row.uncertain) / bits,
                    static_cast<unsigned long long>(row.wrong_certain), double(row.conservative) / bits,
                    double(row.wrong) / cut, double(row.uncertain) / cut);
        out.push_back({{"resolution", row.resolution},
                       {"samples", row.samples},
                       {"table_bytes", row.table_bytes},
                       {"on_demand", row.on_demand},
                       {"bits", row.bits},
                       {"cut_bits", row.cut_bits},
                       {"wrong_bits", row.wrong},
                       {"uncertain_bits", row.uncertain},
                       {"wrong_certain_bits", row.wrong_certain},
                       {"conservative_wrong_bits", row.conservative},
                       {"generate_seconds", row.generate_seconds},
                       {"measure_seconds", row.measure_seconds}});
    }
    if (!json_path.empty()) {
        nlohmann::ordered_json doc = {{"shape", shape}, {"pattern", pattern}, {"mapping", mapping}, {"symmetric", !asymmetric},
                                      {"planes", planes}, {"seed", seed}, {"rows", out}};
        std::ofstream(json_path) << doc.dump(2) << "\n";
    }
    uint64_t wrong_certain = 0;
    for (const Row& row : rows) wrong_certain += row.wrong_certain;
    return wrong_certain == 0 ? 0 : 2;
}
