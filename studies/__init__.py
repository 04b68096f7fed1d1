"""One-off studies and checks beside the package: README.md says what each found."""
