"""Drawing and plotting (headless: frames and images are written to files)."""
