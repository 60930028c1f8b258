// Which copy of the contact pipeline a world runs (contact_stages.h): in the x86-64 baseline build
// the widest of SSE2, AVX2 with FMA and AVX-512 the core has, or the one named; in a build for one
// instruction set, that one. CMake compiles the pipeline once per set, each copy in a namespace of
// its own and linked with every symbol local but its entry (engine/CMakeLists.txt), so no code of
// a wider set is ever shared with, or called from, the baseline code.
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "contact_stages.h"
#include "simd.h"

// each copy's entry, defined in its contact_solver.cpp
#if defined(RTP_CONTACT_DISPATCH)
extern "C" const rtp::ContactIsa* rtp_contact_isa_x86_64();
extern "C" const rtp::ContactIsa* rtp_contact_isa_x86_64_v3();
extern "C" const rtp::ContactIsa* rtp_contact_isa_x86_64_v4();
#else
extern "C" const rtp::ContactIsa* rtp_contact_isa_native();
#endif

namespace rtp {

ContactStages::~ContactStages() = default;

namespace {

// the copies this build carries that this core runs, widest first, each checked to see the
// world's types as the world does
std::vector<const ContactIsa*> runnable() {
  std::vector<const ContactIsa*> out;
#if defined(RTP_CONTACT_DISPATCH)
  if (simd::core_runs_x86_64_v4()) out.push_back(rtp_contact_isa_x86_64_v4());
  if (simd::core_runs_x86_64_v3()) out.push_back(rtp_contact_isa_x86_64_v3());
  out.push_back(rtp_contact_isa_x86_64());
#else
  out.push_back(rtp_contact_isa_native());
#endif
  for (const ContactIsa* isa : out)
    if (!(isa->interface_layout == kContactInterfaceLayout))
      throw std::logic_error(std::string("rtp: the contact passes for ") + isa->name +
                             " were compiled with another layout of the world's types (a " +
                             "BodyState of " + std::to_string(isa->interface_layout.body_state) +
                             " bytes against " +
                             std::to_string(kContactInterfaceLayout.body_state) +
                             ", …): a build error, see engine/CMakeLists.txt");
  return out;
}

std::string names(const std::vector<const ContactIsa*>& isas) {
  std::string out;
  for (const ContactIsa* isa : isas) out += (out.empty() ? "" : ", ") + std::string(isa->name);
  return out;
}

}  // namespace

const ContactIsa& contact_isa(const std::string& wanted) {
  static const std::vector<const ContactIsa*> isas = runnable();
  std::string name = wanted;
  const char* from = "ContactSettings::instruction_set";
  if (name.empty()) {
    const char* variable = std::getenv("RTP_CONTACT_ISA");
    if (variable == nullptr || *variable == '\0') return *isas.front();
    name = variable;
    from = "the environment variable RTP_CONTACT_ISA";
  }
  for (const ContactIsa* isa : isas)
    if (name == isa->name) return *isa;
  throw std::invalid_argument("rtp: " + std::string(from) + " asks for the contact passes of '" +
                              name + "'; this build carries, and this core runs: " +
                              names(isas));
}

// what a world made with the default settings runs
std::size_t contact_block_lanes() { return contact_isa("").block_lanes; }

const char* instruction_set() {
#if defined(RTP_CONTACT_DISPATCH)
  static const std::string words = std::string(simd::kInstructionSet) +
                                   "; the contact passes chosen at run time: " +
                                   contact_isa("").name + " (" + contact_isa("").instructions +
                                   ")";
  return words.c_str();
#else
  return simd::kInstructionSet;
#endif
}

}  // namespace rtp
