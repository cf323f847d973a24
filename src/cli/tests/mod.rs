//! The command line's machinery: every parser of what a user hands the command line replayed
//! on the fuzzers' corpus.

mod corpus;
