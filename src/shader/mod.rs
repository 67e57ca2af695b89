//! The shading language: lexer, parser, checker, one interpreter generic over the number type,
//! and the adaptive quadtree sampler.

pub mod rng;
