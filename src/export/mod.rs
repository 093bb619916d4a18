//! Writers for draped nets: the JSON contract, VTU (ParaView) and CSV.
