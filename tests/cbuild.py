"""How the tests build exported C: every warning an error; -O1, which compiles the large
generated files about three times faster than the Makefile's default -O2 (the generated NLP
of an order4 problem is megabytes of C) and runs the small test instances as well."""

CFLAGS = "-O1 -Wall -Wextra -Werror"

#: for tests of what the exported binary writes, not of how fast it runs: -O0 compiles the
#: generated NLP about twice as fast again, with the same warnings made errors
CFLAGS_QUICK = "-O0 -Wall -Wextra -Werror"
