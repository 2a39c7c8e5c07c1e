// libFuzzer target: arbitrary bytes through the packet parser (in two chunks, to exercise partial
// packets), every packet through the SIP, SYNC2 and command decoders; a decoded SIP must survive a
// re-encode round trip.
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "scanstop_pioneer/p2os_protocol.h"

using namespace scanstop::pioneer;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  PacketParser parser;
  const size_t split = size ? data[0] % (size + 1) : 0;
  parser.feed(data, split);
  std::vector<uint8_t> payload;
  size_t packets = 0;
  for (int round = 0; round < 2; ++round) {
    while (parser.next(payload)) {
      ++packets;
      if (payload.empty() || payload.size() > kMaxPayload) std::abort();
      Sip sip;
      if (decodeSip(payload.data(), payload.size(), sip)) {
        const std::vector<uint8_t> again = encodeSip(sip);
        Sip back;
        if (!decodeSip(again.data(), again.size(), back) || back.x != sip.x || back.th != sip.th ||
            back.sonar.size() != sip.sonar.size())
          std::abort();
      }
      SyncInfo info;
      decodeSync2Reply(payload.data(), payload.size(), info);
      ClientCommand command;
      decodeCommand(payload.data(), payload.size(), command);
    }
    if (round == 0) parser.feed(data + split, size - split);
  }
  if (parser.buffered() > kMaxCount + 3) std::abort();  // the backlog stays bounded
  // Raw bytes straight into the decoders too.
  Sip sip;
  decodeSip(data, size, sip);
  SyncInfo info;
  decodeSync2Reply(data, size, info);
  (void)packets;
  return 0;
}
