#pragma once
/// Raw serial line setup (termios) shared by the drivers (pioneer_driver, rotating_urg_driver) and
/// their pseudo-terminal emulators.

#include <string>

namespace scanstop {

/// True when configureRawSerial accepts this rate [baud].
bool isSupportedBaud(int baud);
/// The accepted rates as text ("9600, 19200, ..."), for error messages.
std::string supportedBauds();

/// Puts fd into raw 8N1 mode without flow control, with non-blocking reads (VMIN = VTIME = 0), at
/// `baud` (0 keeps the current speed, e.g. on a pseudo-terminal). Returns false with errno set on
/// failure (not a terminal: ENOTTY; an unsupported rate: EINVAL).
bool configureRawSerial(int fd, int baud);

}  // namespace scanstop
