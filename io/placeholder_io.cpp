namespace atelier::io_detail { int io_unit = 0; }
