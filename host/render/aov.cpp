// The AOV layers (see aov.h).
#include "render/aov.h"

#include <algorithm>

#include "scene/json_reader.h"
#include "util/error.h"

namespace vkray {

namespace {

const char* const kAovFlag = "--aov";

std::string aovChoices() {
  std::string list;
  for (const auto& entry : EnumNames<Aov>::values) list += "'" + std::string(entry.name) + "', ";
  return list + "or 'all'";
}

std::string trimmed(const std::string& s) {
  const auto begin = s.find_first_not_of(" \t");
  if (begin == std::string::npos) return {};
  return s.substr(begin, s.find_last_not_of(" \t") - begin + 1);
}

bool has(const std::vector<Aov>& aovs, Aov a) {
  return std::find(aovs.begin(), aovs.end(), a) != aovs.end();
}

// One channel per pixel from a member of each record.
template <class Record, class Get>
ExrChannel channel(const std::string& name, const std::vector<Record>& records, Get get) {
  ExrChannel c{name, std::vector<float>(records.size())};
  std::transform(records.begin(), records.end(), c.values.begin(), get);
  return c;
}

ExrChannel statChannel(Aov aov, const std::vector<float>& values, std::size_t pixelCount) {
  const std::string name(enumName(aov));
  if (values.size() != pixelCount) {
    throw Error("--aov " + name + ": the render returned " + std::to_string(values.size()) + " values for " +
                std::to_string(pixelCount) + " pixels");
  }
  return ExrChannel{name + ".Y", values};
}

} // namespace

std::vector<Aov> parseAovList(const std::string& list) {
  if (trimmed(list).empty()) throw InputError(kAovFlag, "the list is empty: name one or more of " + aovChoices());
  std::vector<bool> wanted(EnumNames<Aov>::values.size(), false);
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = list.find(',', start);
    const std::string name =
        trimmed(list.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (name.empty()) {
      throw InputError(kAovFlag, "an empty name in '" + list + "': names are separated by single commas");
    }
    if (name == "all") {
      std::fill(wanted.begin(), wanted.end(), true);
    } else if (auto aov = parseEnum<Aov>(name)) {
      wanted[static_cast<std::size_t>(*aov)] = true;
    } else {
      std::vector<std::string> names = enumNameList<Aov>();
      names.push_back("all");
      const std::string guess = closestMatch(name, names);
      throw InputError(kAovFlag, "unknown AOV '" + name + "'" +
                                     (guess.empty() ? "" : " (did you mean '" + guess + "'?)") +
                                     "; known: " + aovChoices());
    }
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  std::vector<Aov> aovs;
  for (const auto& entry : EnumNames<Aov>::values) {
    if (wanted[static_cast<std::size_t>(entry.value)]) aovs.push_back(entry.value);
  }
  return aovs;
}

bool needsFirstHits(const std::vector<Aov>& aovs) {
  return has(aovs, Aov::Depth) || has(aovs, Aov::Normal) || has(aovs, Aov::Albedo);
}

bool needsPixelStats(const std::vector<Aov>& aovs) {
  return has(aovs, Aov::Spp) || has(aovs, Aov::Error) || has(aovs, Aov::Rays);
}

void checkPixelStats(const std::vector<Aov>& aovs, const PixelStats& pixels) {
  if (!needsPixelStats(aovs) || !pixels.empty()) return;
  std::string where = kAovFlag;
  char separator = ' ';
  for (Aov a : {Aov::Spp, Aov::Error, Aov::Rays}) {
    if (!has(aovs, a)) continue;
    where += separator;
    where += enumName(a);
    separator = ',';
  }
  throw InputError(where, "the renderer returned no per-pixel statistics (samples, error, rays); the progressive "
                          "renderer that keeps them is not in this build");
}

std::vector<ExrChannel> aovChannels(const std::vector<Aov>& aovs, const std::vector<FirstHit>& firstHits,
                                    const PixelStats& pixels, std::size_t pixelCount) {
  checkPixelStats(aovs, pixels);
  if (needsFirstHits(aovs) && firstHits.size() != pixelCount) {
    throw Error("--aov: the first-hit pass returned " + std::to_string(firstHits.size()) + " pixels of " +
                std::to_string(pixelCount));
  }
  std::vector<ExrChannel> channels;
  for (Aov aov : aovs) {
    switch (aov) {
    case Aov::Depth:
      channels.push_back(channel("depth.Z", firstHits, [](const FirstHit& h) { return h.depth; }));
      break;
    case Aov::Normal:
      for (int c = 0; c < 3; ++c) {
        const char* axis[] = {"X", "Y", "Z"};
        channels.push_back(
            channel(std::string("normal.") + axis[c], firstHits, [c](const FirstHit& h) { return h.normal[c]; }));
      }
      break;
    case Aov::Albedo:
      for (int c = 0; c < 3; ++c) {
        const char* rgb[] = {"R", "G", "B"};
        channels.push_back(
            channel(std::string("albedo.") + rgb[c], firstHits, [c](const FirstHit& h) { return h.albedo[c]; }));
      }
      break;
    case Aov::Spp:
      channels.push_back(statChannel(aov, pixels.samples, pixelCount));
      break;
    case Aov::Error:
      channels.push_back(statChannel(aov, pixels.error, pixelCount));
      break;
    case Aov::Rays:
      channels.push_back(statChannel(aov, pixels.rays, pixelCount));
      break;
    }
  }
  return channels;
}

} // namespace vkray
