#include "experiments/cli/cli.h"

int main(int argc, char** argv) { return springlab::run_cli(argc, argv); }
