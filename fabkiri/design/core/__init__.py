"""What every design solver shares: the Levenberg-Marquardt core, sparse stencils, requests and conformance."""
