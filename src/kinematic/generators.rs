//! Generators: the two fibre paths through the origin node that seed the fishnet.
