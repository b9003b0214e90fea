// The one source file of handemo_example_transfer that compiles the definitions of <handemo/transfer.hpp>.
#include <handemo/transfer_impl.hpp>
