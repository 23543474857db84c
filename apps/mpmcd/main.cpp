// mpmcd command line: all logic lives in the app module (src/app/cli.cpp).
#include "mpmcd/app/cli.hpp"

int main(int argc, char** argv) { return mpmcd::app::run_cli(argc, argv); }
