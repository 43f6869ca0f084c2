"""Chip emulators behind the edge's bus ports: ADS1x15 ADC, MCP4725 DAC, GPIO lines."""
