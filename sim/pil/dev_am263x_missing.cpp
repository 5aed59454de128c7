// Built when sim/pil/dev_am263x.cpp (the TI AM263x port's register model) is absent: an image
// of that port is refused at load time with this reason.
#include "pil.hpp"

namespace mcsim::pil {

std::unique_ptr<Peripherals> make_am263x_peripherals()
{
    throw LoadError("am263x port model not built");
}

}  // namespace mcsim::pil
