"""Analysis of simulated or measured images: statistics, correlation, tracking, strain."""
